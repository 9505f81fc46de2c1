//! A static kd-tree over points in `D` dimensions, as flat arrays: nodes in depth-first
//! pre-order, each owning a contiguous range of a permutation of the input, so a node's items
//! are `order[start..end]` and its aggregates can be summed over that slice.
//!
//! Built top-down by splitting each node's bounding box along its largest extent at the median
//! item (Milaenen et al. 2019 §5: "kd-trees, split along the largest bounding volume
//! dimension"; the flat layout with index ranges is Mitsuba's `StaticOctree` idea). A node
//! becomes a leaf when it holds at most `leaf_size` items. Items with equal coordinates (e.g.
//! several camera samples of one pixel) are still split by count, so every leaf respects
//! `leaf_size`.
//!
//! The build is O(N log N): each level costs a bounding box and one `select_nth_unstable` per
//! node. Subtrees with many items are built in parallel (`rayon::join`) and concatenated in a
//! fixed order, so the tree does not depend on the thread count.

/// Sentinel child index of a leaf.
pub const LEAF: u32 = u32::MAX;

/// Subtrees with more items than this are built with `rayon::join`.
const PARALLEL_ITEMS: usize = 1 << 15;

/// One node of a [`KdTree`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KdNode<const D: usize> {
    /// Lower corner of the bounding box of the node's points.
    pub lo: [f64; D],
    /// Upper corner of the bounding box of the node's points.
    pub hi: [f64; D],
    /// The node's items are `order[start..end]`.
    pub start: u32,
    /// End of the node's range (exclusive).
    pub end: u32,
    /// Index of the left child, or [`LEAF`]. The left child's range is `start..mid`.
    pub left: u32,
    /// Index of the right child, or [`LEAF`]. The right child's range is `mid..end`.
    pub right: u32,
}

impl<const D: usize> KdNode<D> {
    /// True for a leaf.
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.left == LEAF
    }

    /// Number of items under the node.
    #[inline]
    pub fn len(&self) -> usize {
        (self.end - self.start) as usize
    }

    /// True if the node holds no item (only the root of an empty tree).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.end == self.start
    }

    /// The largest side of the bounding box.
    #[inline]
    pub fn extent(&self) -> f64 {
        let mut e: f64 = 0.0;
        for k in 0..D {
            e = e.max(self.hi[k] - self.lo[k]);
        }
        e
    }
}

/// A kd-tree: nodes (root first, pre-order) and the permutation of the items.
#[derive(Clone, Debug, PartialEq)]
pub struct KdTree<const D: usize> {
    /// Nodes, depth-first pre-order; `nodes[0]` is the root (absent for no items).
    pub nodes: Vec<KdNode<D>>,
    /// Item indices (into the input) in leaf order: node `n` holds
    /// `order[n.start..n.end]`.
    pub order: Vec<u32>,
}

impl<const D: usize> KdTree<D> {
    /// Builds the tree over `points` with at most `leaf_size` (≥ 1) items per leaf.
    ///
    /// # Panics
    /// If there are more than `u32::MAX - 1` points (callers cap their inputs far below).
    pub fn build(points: &[[f64; D]], leaf_size: usize) -> Self {
        assert!(
            points.len() < LEAF as usize,
            "too many points for a kd-tree"
        );
        let leaf_size = leaf_size.max(1);
        let mut order: Vec<u32> = (0..points.len() as u32).collect();
        if points.is_empty() {
            return KdTree {
                nodes: Vec::new(),
                order,
            };
        }
        let nodes = build_range(points, &mut order, 0, leaf_size);
        KdTree { nodes, order }
    }

    /// The root, if the tree has items.
    pub fn root(&self) -> Option<&KdNode<D>> {
        self.nodes.first()
    }

    /// Per node, a summary of its items computed bottom-up in one reverse pass (children
    /// come after their parent in pre-order): `leaf(node)` for a leaf, `combine(left, right)`
    /// for an inner node. With an associative `combine` each node's value equals the one
    /// computed directly over its range.
    pub fn bottom_up<T: Copy>(
        &self,
        empty: T,
        leaf: impl Fn(&KdNode<D>) -> T,
        combine: impl Fn(&T, &T) -> T,
    ) -> Vec<T> {
        let mut out = vec![empty; self.nodes.len()];
        for (k, node) in self.nodes.iter().enumerate().rev() {
            out[k] = if node.is_leaf() {
                leaf(node)
            } else {
                combine(&out[node.left as usize], &out[node.right as usize])
            };
        }
        out
    }

    /// The item indices of node `n`.
    #[inline]
    pub fn items(&self, n: &KdNode<D>) -> &[u32] {
        &self.order[n.start as usize..n.end as usize]
    }
}

/// Bounding box of the points `order` refers to.
fn bounds<const D: usize>(points: &[[f64; D]], order: &[u32]) -> ([f64; D], [f64; D]) {
    let mut lo = [f64::INFINITY; D];
    let mut hi = [f64::NEG_INFINITY; D];
    for &i in order {
        let p = &points[i as usize];
        for k in 0..D {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// Builds the subtree over `order` (a slice of the permutation starting at item `offset`),
/// returning its nodes with indices local to the returned vector.
fn build_range<const D: usize>(
    points: &[[f64; D]],
    order: &mut [u32],
    offset: u32,
    leaf_size: usize,
) -> Vec<KdNode<D>> {
    let (lo, hi) = bounds(points, order);
    let n = order.len();
    let mut node = KdNode {
        lo,
        hi,
        start: offset,
        end: offset + n as u32,
        left: LEAF,
        right: LEAF,
    };
    if n <= leaf_size {
        return vec![node];
    }
    let mut axis = 0;
    for k in 1..D {
        if hi[k] - lo[k] > hi[axis] - lo[axis] {
            axis = k;
        }
    }
    let mid = n / 2;
    if hi[axis] > lo[axis] {
        // Median along the axis; ties broken by item index so the split is a function of the
        // input alone.
        order.select_nth_unstable_by(mid, |&a, &b| {
            points[a as usize][axis]
                .total_cmp(&points[b as usize][axis])
                .then(a.cmp(&b))
        });
    }
    // (All points equal: split by count in input order.)
    let (left_items, right_items) = order.split_at_mut(mid);
    let (left, right) = if n > PARALLEL_ITEMS {
        rayon::join(
            || build_range(points, left_items, offset, leaf_size),
            || build_range(points, right_items, offset + mid as u32, leaf_size),
        )
    } else {
        (
            build_range(points, left_items, offset, leaf_size),
            build_range(points, right_items, offset + mid as u32, leaf_size),
        )
    };
    let mut nodes = Vec::with_capacity(1 + left.len() + right.len());
    node.left = 1;
    node.right = 1 + left.len() as u32;
    nodes.push(node);
    append_shifted(&mut nodes, left, 1);
    let shift = node.right;
    append_shifted(&mut nodes, right, shift);
    nodes
}

/// Appends `sub` (indices local to it) to `nodes`, shifting its child indices by `shift`.
fn append_shifted<const D: usize>(nodes: &mut Vec<KdNode<D>>, sub: Vec<KdNode<D>>, shift: u32) {
    nodes.extend(sub.into_iter().map(|mut c| {
        if !c.is_leaf() {
            c.left += shift;
            c.right += shift;
        }
        c
    }));
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check<const D: usize>(points: &[[f64; D]], leaf: usize) {
        let t = KdTree::build(points, leaf);
        let mut seen = vec![false; points.len()];
        for &i in &t.order {
            assert!(!seen[i as usize], "item {i} twice");
            seen[i as usize] = true;
        }
        assert!(seen.iter().all(|&s| s));
        for n in &t.nodes {
            for &i in t.items(n) {
                for (k, &x) in points[i as usize].iter().enumerate() {
                    assert!(n.lo[k] <= x && x <= n.hi[k]);
                }
            }
            if n.is_leaf() {
                assert!(n.len() <= leaf);
            } else {
                let (l, r) = (&t.nodes[n.left as usize], &t.nodes[n.right as usize]);
                assert_eq!(l.start, n.start);
                assert_eq!(l.end, r.start);
                assert_eq!(r.end, n.end);
                assert!(!l.is_empty() && !r.is_empty());
            }
        }
    }

    #[test]
    fn ranges_partition_and_bounds_contain() {
        let mut s = 1u64;
        let mut pts = Vec::new();
        for _ in 0..5000 {
            let mut p = [0.0; 3];
            for x in &mut p {
                s = sss_util::splitmix64(s);
                *x = (s >> 11) as f64 / (1u64 << 53) as f64;
            }
            pts.push(p);
        }
        for leaf in [1, 4, 7] {
            check(&pts, leaf);
        }
        // Many duplicates (camera samples of one pixel share coordinates).
        let dup: Vec<[f64; 2]> = (0..1000).map(|i| [(i / 16) as f64, 0.0]).collect();
        check(&dup, 2);
        let same = vec![[1.0, 1.0]; 100];
        check(&same, 3);
        check::<2>(&[], 3);
    }
}
