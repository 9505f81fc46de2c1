//! The kd-trees over irradiance samples and pixels: every node's aggregates equal brute-force
//! sums over its range, the ranges partition the items, and the build does not depend on the
//! thread count.

use glam::DVec3;
use sss_hierarchy::{IrradiancePoint, IrradianceTree, PixelPoint, PixelTree};

fn uniform(state: &mut u64) -> f64 {
    *state = sss_util::splitmix64(*state);
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

fn irradiance_points(n: usize, seed: u64) -> Vec<IrradiancePoint> {
    let mut s = seed;
    (0..n)
        .map(|i| {
            let position = DVec3::new(uniform(&mut s), 3.0 * uniform(&mut s), uniform(&mut s));
            // Every tenth sample dark, so some nodes need the area-weighted fallback.
            let e = if i % 10 == 0 {
                [0.0; 3]
            } else {
                [uniform(&mut s), 2.0 * uniform(&mut s), uniform(&mut s)]
            };
            IrradiancePoint {
                position,
                area: 0.01 + uniform(&mut s),
                irradiance: e,
            }
        })
        .collect()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * (1.0 + a.abs().max(b.abs()))
}

#[test]
fn irradiance_aggregates_equal_brute_force_sums() {
    let input = irradiance_points(3000, 5);
    for leaf in [1, 4, 8] {
        let t = IrradianceTree::build(&input, leaf);
        assert_eq!(t.clusters.len(), t.tree.nodes.len());
        let total_area: f64 = input.iter().map(|p| p.area).sum();
        assert!(close(t.clusters[0].area, total_area));
        for (node, cl) in t.tree.nodes.iter().zip(&t.clusters) {
            assert!(node.len() <= leaf || !node.is_leaf());
            // Brute force over the node's input items (through the permutation, not the
            // tree's reordered copy).
            let items: Vec<&IrradiancePoint> = t
                .tree
                .items(node)
                .iter()
                .map(|&i| &input[i as usize])
                .collect();
            let area: f64 = items.iter().map(|p| p.area).sum();
            assert!(close(cl.area, area), "area {} vs {area}", cl.area);
            for c in 0..3 {
                let flux: f64 = items.iter().map(|p| p.irradiance[c] * p.area).sum();
                assert!(close(cl.flux[c], flux));
            }
            let lum = |p: &IrradiancePoint| {
                (0.2126 * p.irradiance[0] + 0.7152 * p.irradiance[1] + 0.0722 * p.irradiance[2])
                    * p.area
            };
            let w: f64 = items.iter().map(|p| lum(p)).sum();
            let expected = if w > 0.0 {
                items.iter().map(|p| p.position * lum(p)).sum::<DVec3>() / w
            } else {
                items.iter().map(|p| p.position * p.area).sum::<DVec3>() / area
            };
            assert!(
                cl.position.distance(expected) < 1e-9,
                "{:?} vs {expected:?}",
                cl.position
            );
            for p in &items {
                for k in 0..3 {
                    assert!(node.lo[k] <= p.position[k] && p.position[k] <= node.hi[k]);
                }
            }
            // The reordered copy holds the same samples.
            for (k, &i) in t.tree.items(node).iter().enumerate() {
                assert_eq!(t.points_of(node)[k].position, input[i as usize].position);
            }
        }
    }
}

#[test]
fn dark_nodes_use_area_weights_and_bad_values_count_as_zero() {
    let mut input = irradiance_points(64, 9);
    for p in &mut input {
        p.irradiance = [0.0; 3];
    }
    input[3].area = f64::NAN;
    input[4].area = -1.0;
    input[5].irradiance = [f64::INFINITY, -2.0, 1.0];
    let t = IrradianceTree::build(&input, 4);
    let area: f64 = input
        .iter()
        .map(|p| if p.area > 0.0 { p.area } else { 0.0 })
        .sum();
    assert!(close(t.clusters[0].area, area));
    assert!(close(t.clusters[0].flux[2], input[5].area));
    assert_eq!(t.clusters[0].flux[0], 0.0);
    assert_eq!(t.clusters[0].flux[1], 0.0);
    for cl in &t.clusters {
        assert!(cl.position.is_finite());
    }
}

fn pixel_points(w: u32, h: u32, spp: u32) -> Vec<PixelPoint> {
    let mut s = 17u64;
    let mut out = Vec::new();
    for y in 0..h {
        for x in 0..w {
            for _ in 0..spp {
                let n = DVec3::new(uniform(&mut s) - 0.5, 1.0, 0.1).normalize();
                let v = DVec3::new(0.3 * uniform(&mut s), -0.2 * uniform(&mut s), 1.0);
                out.push(PixelPoint {
                    screen: [x as f64 + 0.5, y as f64 + 0.5],
                    position: DVec3::new(x as f64, y as f64, 5.0 + uniform(&mut s)),
                    normal: n,
                    view: v.normalize(),
                    rate: uniform(&mut s) * 0.4,
                });
            }
        }
    }
    out
}

#[test]
fn pixel_aggregates_equal_brute_force_and_length_is_in_pixels() {
    let input = pixel_points(37, 23, 2);
    let t = PixelTree::build(&input, 4);
    for (node, cl) in t.tree.nodes.iter().zip(&t.clusters) {
        let items: Vec<&PixelPoint> = t
            .tree
            .items(node)
            .iter()
            .map(|&i| &input[i as usize])
            .collect();
        let n = items.len() as f64;
        let mean = items.iter().map(|p| p.position).sum::<DVec3>() / n;
        assert!(cl.position.distance(mean) < 1e-9);
        let mean_n = items.iter().map(|p| p.normal).sum::<DVec3>() / n;
        assert!(cl.normal.distance(mean_n) < 1e-12);
        let mean_v = items.iter().map(|p| p.view).sum::<DVec3>() / n;
        assert!(cl.view.distance(mean_v) < 1e-12);
        let rate = items.iter().map(|p| p.rate).fold(0.0, f64::max);
        assert_eq!(cl.max_rate, rate);
        let lo = items.iter().fold(DVec3::INFINITY, |a, p| a.min(p.position));
        let hi = items
            .iter()
            .fold(DVec3::NEG_INFINITY, |a, p| a.max(p.position));
        assert_eq!((cl.world_lo, cl.world_hi), (lo, hi));
        // LENGTH: the largest side of the screen box of pixel centres.
        let xs = items.iter().map(|p| p.screen[0]);
        let ys = items.iter().map(|p| p.screen[1]);
        let span = |v: &mut dyn Iterator<Item = f64>| {
            let (mut a, mut b) = (f64::INFINITY, f64::NEG_INFINITY);
            for x in v {
                a = a.min(x);
                b = b.max(x);
            }
            b - a
        };
        let len = span(&mut xs.clone()).max(span(&mut ys.clone()));
        assert_eq!(t.length_px(node), len);
    }
    // The root spans the image: 36 pixels across.
    assert_eq!(t.length_px(&t.tree.nodes[0]), 36.0);
}

#[test]
fn builds_do_not_depend_on_the_thread_count() {
    // Large enough for the parallel build (> 2^15 items per subtree).
    let input = pixel_points(300, 250, 1);
    let pool = |n| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    };
    let a = pool(1).install(|| PixelTree::build(&input, 4));
    let b = pool(2).install(|| PixelTree::build(&input, 4));
    assert_eq!(a.tree, b.tree);
    assert_eq!(a.clusters, b.clusters);
    let irr = irradiance_points(70_000, 3);
    let a = pool(1).install(|| IrradianceTree::build(&irr, 1));
    let b = pool(2).install(|| IrradianceTree::build(&irr, 1));
    assert_eq!(a.tree, b.tree);
    assert_eq!(a.clusters, b.clusters);
}

#[test]
fn byte_estimates_bound_the_trees() {
    for (n, leaf) in [(1000, 1), (5000, 4), (777, 8)] {
        let t = IrradianceTree::build(&irradiance_points(n, 1), leaf);
        let used = t.tree.nodes.len() * std::mem::size_of_val(&t.tree.nodes[0])
            + t.clusters.len() * std::mem::size_of_val(&t.clusters[0])
            + n * (4 + std::mem::size_of::<IrradiancePoint>());
        assert!(
            (used as u64) <= IrradianceTree::bytes_for(n, leaf),
            "{n} {leaf}"
        );
    }
    let input = pixel_points(50, 40, 1);
    let t = PixelTree::build(&input, 4);
    let used = t.tree.nodes.len() * std::mem::size_of_val(&t.tree.nodes[0])
        + t.clusters.len() * std::mem::size_of_val(&t.clusters[0])
        + input.len() * 4;
    assert!((used as u64) <= PixelTree::bytes_for(input.len(), 4));
}

/// The build rule of `KdTree`, checked on every node against brute force over its own items:
/// the node holds at least one item; the node's box is the tight box of its items; a leaf holds 1..=leaf_size items; an inner
/// node's children split its range, the left one taking ⌊n/2⌋ items, and along an axis of the
/// node box's largest side no left item lies beyond a right one (the median split along the
/// largest extent, Milaenen et al. 2019 §5).
fn check_median_splits<const D: usize>(points: &[[f64; D]], leaf: usize) {
    let t = sss_hierarchy::KdTree::build(points, leaf);
    let root = t.root().expect("items, so a root");
    assert_eq!((root.start, root.end), (0, points.len() as u32));
    let mut seen = vec![false; points.len()];
    for &i in &t.order {
        assert!(
            !std::mem::replace(&mut seen[i as usize], true),
            "item {i} twice"
        );
    }
    assert!(seen.iter().all(|&s| s));
    for (id, n) in t.nodes.iter().enumerate() {
        let items = t.items(n);
        // Every node of a built tree holds items (an empty input has no nodes at all).
        assert!(!items.is_empty() && !n.is_empty(), "node {id}: empty");
        let (mut lo, mut hi) = ([f64::INFINITY; D], [f64::NEG_INFINITY; D]);
        for &i in items {
            for k in 0..D {
                lo[k] = lo[k].min(points[i as usize][k]);
                hi[k] = hi[k].max(points[i as usize][k]);
            }
        }
        assert_eq!((n.lo, n.hi), (lo, hi), "node {id}: box");
        if n.is_leaf() {
            assert!(
                (1..=leaf).contains(&n.len()),
                "leaf {id}: {} items",
                n.len()
            );
            continue;
        }
        let (l, r) = (&t.nodes[n.left as usize], &t.nodes[n.right as usize]);
        assert_eq!(
            (l.start, l.end, r.start, r.end),
            (
                n.start,
                n.start + n.len() as u32 / 2,
                n.start + n.len() as u32 / 2,
                n.end
            ),
            "node {id}: ranges"
        );
        let widest = (0..D).map(|k| hi[k] - lo[k]).fold(0.0, f64::max);
        if widest == 0.0 {
            continue;
        }
        let separated = (0..D).filter(|&k| hi[k] - lo[k] == widest).any(|k| {
            let left_max = t
                .items(l)
                .iter()
                .map(|&i| points[i as usize][k])
                .fold(f64::NEG_INFINITY, f64::max);
            let right_min = t
                .items(r)
                .iter()
                .map(|&i| points[i as usize][k])
                .fold(f64::INFINITY, f64::min);
            left_max <= right_min
        });
        assert!(
            separated,
            "node {id}: not split at the median of its widest side"
        );
    }
}

#[test]
fn every_inner_node_splits_at_the_median_of_its_longest_side() {
    let mut s = 21u64;
    // Anisotropic: the widest side changes from node to node.
    let pts: Vec<[f64; 3]> = (0..5000)
        .map(|_| {
            [
                uniform(&mut s),
                3.0 * uniform(&mut s),
                0.5 * uniform(&mut s),
            ]
        })
        .collect();
    for leaf in [1, 4, 7] {
        check_median_splits(&pts, leaf);
    }
    // Pixel centres with several samples each (ties), and more than the 2^15 items above
    // which subtrees are built in parallel.
    let pix: Vec<[f64; 2]> = (0..40_000)
        .map(|i| [((i / 3) % 230) as f64 + 0.5, (i / 690) as f64 + 0.5])
        .collect();
    check_median_splits(&pix, 4);
    check_median_splits(&[[1.0, 1.0]; 100], 3);
    let empty = sss_hierarchy::KdTree::<2>::build(&[], 3);
    assert!(empty.nodes.is_empty() && empty.root().is_none());
    // A node over an empty range (public fields: a caller can make one) is empty.
    let none = sss_hierarchy::KdNode::<2> {
        lo: [0.0; 2],
        hi: [0.0; 2],
        start: 3,
        end: 3,
        left: sss_hierarchy::kdtree::LEAF,
        right: sss_hierarchy::kdtree::LEAF,
    };
    assert!(none.is_empty() && none.is_leaf());
    assert_eq!(none.len(), 0);
}

/// The byte estimates cover what a build holds at its end and follow the leaf size. The
/// irradiance tree's counts the samples twice (the caller's copy it is built from and the
/// tree's own), the pixel tree's the 2-D coordinates the build copies; both assume leaves of
/// ⌊leaf/2⌋ items (a median split never makes them smaller, so at most twice the nodes), so
/// for leaf sizes 1 and even ones they stay below twice what is held. Doubling the leaf size
/// (from 2 on) shrinks the built tree and the estimate.
#[test]
fn byte_estimates_follow_the_leaf_size() {
    let n = 5000;
    let input = irradiance_points(n, 2);
    estimates_bound_what_is_held(|leaf| {
        let t = IrradianceTree::build(&input, leaf);
        let held = (t.tree.nodes.len() * std::mem::size_of_val(&t.tree.nodes[0])
            + t.clusters.len() * std::mem::size_of_val(&t.clusters[0])
            + n * (4 + 2 * std::mem::size_of::<IrradiancePoint>())) as u64;
        (held, IrradianceTree::bytes_for(n, leaf))
    });
    let input = pixel_points(60, 50, 1);
    let n = input.len();
    estimates_bound_what_is_held(|leaf| {
        let t = PixelTree::build(&input, leaf);
        let held = (t.tree.nodes.len() * std::mem::size_of_val(&t.tree.nodes[0])
            + t.clusters.len() * std::mem::size_of_val(&t.clusters[0])
            + n * (4 + std::mem::size_of::<[f64; 2]>())) as u64;
        (held, PixelTree::bytes_for(n, leaf))
    });
}

/// For leaf sizes 1 … 16, `held_and_estimate(leaf)` gives the bytes a built tree holds and its
/// estimate: the estimate bounds what is held, by less than 2×, and both shrink at each
/// doubling of the leaf size from 2 → 4 on.
fn estimates_bound_what_is_held(held_and_estimate: impl Fn(usize) -> (u64, u64)) {
    let mut last = (u64::MAX, u64::MAX);
    for leaf in [1, 2, 4, 8, 16] {
        let (held, est) = held_and_estimate(leaf);
        assert!(
            held <= est && est < 2 * held,
            "leaf {leaf}: estimate {est} B for {held} B held"
        );
        if leaf > 2 {
            assert!(
                held < last.0 && est < last.1,
                "leaf {leaf}: {held} B, {est} B"
            );
        }
        last = (held, est);
    }
}
