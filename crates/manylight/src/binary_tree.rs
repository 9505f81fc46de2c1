//! The one binary tree shape every cluster hierarchy of this crate uses (lights, triangles,
//! shading points): built top-down by median split of item positions along the longest axis
//! of their box, one item per leaf, aggregates filled bottom-up; and the descent that picks a
//! leaf in proportion to the nodes' weights (Walter et al. 2006 build their light and gather
//! trees this way; Nabata & Iwasaki §4.2 use MDLC's trees).

use glam::DVec3;

use crate::aabb::Aabb;

/// Builds the tree over `positions` (one leaf per position) and returns its nodes; the root is
/// node 0 and children always have larger ids than their parent. `leaf(item)` makes the node
/// of one item; `inner(a, b, [ia, ib])` the node over two children.
///
/// Each range is split at its median along the longest axis of its positions' box, ties by
/// index, so the tree is a function of the input alone. Iterative (an explicit stack keeps deep
/// trees off the call stack). `positions` must not be empty.
pub(crate) fn median_split<N: Copy>(
    positions: &[DVec3],
    leaf: impl Fn(u32) -> N,
    inner: impl Fn(&N, &N, [u32; 2]) -> N,
) -> Vec<N> {
    debug_assert!(!positions.is_empty());
    let mut order: Vec<u32> = (0..positions.len() as u32).collect();
    // Per node: its children, or its item.
    let mut shape: Vec<Result<[u32; 2], u32>> = Vec::with_capacity(2 * positions.len());
    shape.push(Err(0));
    let mut stack = vec![(0u32, 0usize, positions.len())];
    while let Some((node, lo, hi)) = stack.pop() {
        let range = &mut order[lo..hi];
        if range.len() == 1 {
            shape[node as usize] = Err(range[0]);
            continue;
        }
        let e = range
            .iter()
            .fold(Aabb::EMPTY, |b, &k| b.grow(positions[k as usize]))
            .extent();
        let axis = if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        };
        // Partition around the median (a total order: position, then index), so each half is
        // the same set a full sort would give, in O(n) instead of O(n log n) per level.
        let half = range.len() / 2;
        range.select_nth_unstable_by(half, |&p, &q| {
            positions[p as usize][axis]
                .total_cmp(&positions[q as usize][axis])
                .then(p.cmp(&q))
        });
        let mid = lo + half;
        let (l, r) = (shape.len() as u32, shape.len() as u32 + 1);
        shape.push(Err(0));
        shape.push(Err(0));
        shape[node as usize] = Ok([l, r]);
        stack.push((l, lo, mid));
        stack.push((r, mid, hi));
    }
    // Children have larger ids: fill from the last node back to the root.
    let mut nodes: Vec<Option<N>> = vec![None; shape.len()];
    for id in (0..shape.len()).rev() {
        nodes[id] = Some(match shape[id] {
            Err(item) => leaf(item),
            Ok([l, r]) => {
                let (a, b) = (nodes[l as usize], nodes[r as usize]);
                inner(&a.expect("child filled"), &b.expect("child filled"), [l, r])
            }
        });
    }
    nodes.into_iter().map(|n| n.expect("filled")).collect()
}

/// Descends from `id` to a leaf, choosing each child in proportion to `weight` (a child of
/// weight 0 is never chosen while its sibling has weight), from one uniform `u` in [0, 1)
/// that is rescaled at each level. `children(id)` gives a node's children (`None` at a leaf).
/// Returns the leaf and its probability (the product of the choices; 0 when a node on the way
/// has total weight 0, whose leftmost leaf is returned).
pub(crate) fn descend(
    mut id: u32,
    mut u: f64,
    children: impl Fn(u32) -> Option<[u32; 2]>,
    weight: impl Fn(u32) -> f64,
) -> (u32, f64) {
    let mut p = 1.0;
    while let Some([a, b]) = children(id) {
        let (wa, wb) = (weight(a), weight(b));
        let w = wa + wb;
        // Also catches a NaN total.
        if w.is_nan() || w <= 0.0 {
            id = a;
            p = 0.0;
            continue;
        }
        let pa = wa / w;
        if u < pa || wb <= 0.0 {
            p *= pa;
            u = if pa > 0.0 {
                (u / pa).min(1.0 - f64::EPSILON)
            } else {
                0.0
            };
            id = a;
        } else {
            let pb = wb / w;
            p *= pb;
            u = ((u - pa) / pb).clamp(0.0, 1.0 - f64::EPSILON);
            id = b;
        }
    }
    (id, p)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A node of a hand-made tree: a leaf with an integer weight, or two children.
    enum Node {
        Leaf(u128),
        Inner(u32, u32),
    }

    /// A tree whose node weights are the f64 roundings of exact integer sums, and the exact
    /// reference: leaf `i` (left to right) owns the half-open interval `[C_i/T, C_{i+1}/T)` of
    /// the cumulative weights, compared with `u` in integer arithmetic.
    struct Tree(Vec<Node>);

    impl Tree {
        fn children(&self, id: u32) -> Option<[u32; 2]> {
            match self.0[id as usize] {
                Node::Leaf(_) => None,
                Node::Inner(a, b) => Some([a, b]),
            }
        }

        fn sum(&self, id: u32) -> u128 {
            match self.0[id as usize] {
                Node::Leaf(w) => w,
                Node::Inner(a, b) => self.sum(a) + self.sum(b),
            }
        }

        fn leaves(&self, id: u32, out: &mut Vec<(u32, u128)>) {
            match self.0[id as usize] {
                Node::Leaf(w) => out.push((id, w)),
                Node::Inner(a, b) => {
                    self.leaves(a, out);
                    self.leaves(b, out);
                }
            }
        }

        fn descend(&self, u: f64) -> (u32, f64) {
            descend(0, u, |id| self.children(id), |id| self.sum(id) as f64)
        }

        /// The leaf whose interval holds `u`, and its exact probability w/T as an f64.
        fn reference(&self, u: f64) -> (u32, f64) {
            // u = m / 2^k exactly (doubling a float below 1 is exact).
            assert!((0.0..1.0).contains(&u));
            let (mut x, mut k) = (u, 0u32);
            while x.fract() != 0.0 {
                x *= 2.0;
                k += 1;
            }
            let (m, scale) = (x as u128, 1u128 << k);
            let total = self.sum(0);
            let at = m.checked_mul(total).expect("fits u128");
            let mut leaves = Vec::new();
            self.leaves(0, &mut leaves);
            let mut c = 0u128;
            for (id, w) in leaves {
                let (lo, hi) = (
                    c.checked_mul(scale).expect("fits"),
                    (c + w).checked_mul(scale).expect("fits"),
                );
                if lo <= at && at < hi {
                    return (id, w as f64 / total as f64);
                }
                c += w;
            }
            unreachable!("u in [0, 1)")
        }
    }

    /// Leaves 3, 4, 5, 7, 8 (left to right) of weights 1, 3, 0, 2, 2 (total 8).
    fn dyadic_tree() -> Tree {
        use Node::*;
        Tree(vec![
            Inner(1, 2),
            Inner(3, 4),
            Inner(5, 6),
            Leaf(1),
            Leaf(3),
            Leaf(0),
            Inner(7, 8),
            Leaf(2),
            Leaf(2),
        ])
    }

    /// Every multiple of 1/64, the interval ends k/8 included (each belongs to the leaf it
    /// starts), picks the leaf of the exact interval with its exact probability; the empty
    /// leaf is never picked.
    #[test]
    fn the_descent_picks_the_leaf_whose_interval_holds_u() {
        let t = dyadic_tree();
        for j in 0..64 {
            let u = j as f64 / 64.0;
            let (leaf, p) = t.descend(u);
            assert_eq!((leaf, p), t.reference(u), "u = {u}");
            assert_ne!(leaf, 5);
        }
        // Random trees with small integer weights (T ≤ 60), u an odd multiple of 2⁻²¹: never
        // an interval's end (a multiple of 1/T) nor within 1e-8 of one.
        let mut s = 3u64;
        let mut next = |n: u64| {
            s = sss_util::splitmix64(s);
            s % n
        };
        for _ in 0..200 {
            let leaves = 1 + next(12) as usize;
            let mut nodes = vec![Node::Leaf(0)];
            let mut open = vec![(0u32, leaves)];
            while let Some((id, n)) = open.pop() {
                if n == 1 {
                    nodes[id as usize] = Node::Leaf(next(6) as u128);
                    continue;
                }
                let left = 1 + next(n as u64 - 1) as usize;
                let (a, b) = (nodes.len() as u32, nodes.len() as u32 + 1);
                nodes.push(Node::Leaf(0));
                nodes.push(Node::Leaf(0));
                nodes[id as usize] = Node::Inner(a, b);
                open.push((a, left));
                open.push((b, n - left));
            }
            let t = Tree(nodes);
            if t.sum(0) == 0 {
                continue;
            }
            for _ in 0..64 {
                let u = (2 * next(1 << 20) + 1) as f64 / (1u64 << 21) as f64;
                let (leaf, p) = t.descend(u);
                let (r, q) = t.reference(u);
                assert_eq!(leaf, r, "u = {u}");
                assert!((p - q).abs() <= 1e-14 * q, "{p} vs {q}");
            }
        }
    }

    /// Where the rescaled u meets the clamps below 1: u/pa and (u − pa)/pb are kept below
    /// 1 − ε, and the leaf still agrees with the exact interval.
    #[test]
    fn the_rescaled_u_stays_below_one_where_rounding_reaches_it() {
        use Node::*;
        // Left branch: pa = fl(1/9) and u its predecessor give u/pa = 1 − 2⁻⁵³, and the left
        // subtree splits (2⁵³ − 1) : 1, so pa' = 1 − 2⁻⁵³; the exact u lies in the first leaf.
        let t = Tree(vec![
            Inner(1, 2),
            Inner(3, 4),
            Leaf(1 << 56),
            Leaf((1 << 53) - 1),
            Leaf(1),
        ]);
        let u = f64::from_bits((1.0f64 / 9.0).to_bits() - 1);
        assert_eq!(t.reference(u).0, 3);
        let (leaf, p) = t.descend(u);
        assert_eq!(leaf, 3);
        assert!((p - t.reference(u).1).abs() < 1e-15);
        // Right branch: pa = fl(1/9), pb = fl(8/9) and u = 1 − 2⁻⁵³ round (u − pa)/pb up to
        // exactly 1; the right subtree splits 2⁷⁰ : 1 (pa' = 1 in f64), and the exact u lies in
        // its first leaf, the last leaf's interval being 1/T ≈ 2⁻⁷⁰ wide.
        let t = Tree(vec![
            Inner(1, 2),
            Leaf(1 << 67),
            Inner(3, 4),
            Leaf(1 << 70),
            Leaf(1),
        ]);
        let u = f64::from_bits(1.0f64.to_bits() - 1);
        assert_eq!(t.reference(u).0, 3);
        let (leaf, p) = t.descend(u);
        assert_eq!(leaf, 3);
        assert!((p - t.reference(u).1).abs() < 1e-15);
    }

    /// A tree of total weight 0 (or NaN) has no distribution: the leftmost leaf, probability 0.
    #[test]
    fn a_weightless_tree_gives_its_leftmost_leaf_with_probability_zero() {
        let t = dyadic_tree();
        for u in [0.0, 0.3, 0.999] {
            assert_eq!(
                descend(0, u, |id| t.children(id), |_| 0.0),
                (3, 0.0),
                "u = {u}"
            );
            assert_eq!(
                descend(0, u, |id| t.children(id), |_| f64::NAN),
                (3, 0.0),
                "u = {u}"
            );
        }
    }
}
