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
                out.push(PixelPoint {
                    screen: [x as f64 + 0.5, y as f64 + 0.5],
                    position: DVec3::new(x as f64, y as f64, 5.0 + uniform(&mut s)),
                    normal: n,
                    view: DVec3::Z,
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
