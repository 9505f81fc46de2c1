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
