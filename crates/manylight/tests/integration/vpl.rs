//! The light tree: structure, sums, normal cones, and sampling with p_L = I(y)/I_node (Eq. 5).

use glam::DVec3;
use sss_manylight::*;

struct U(u64);
impl U {
    fn f(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        (sss_util::splitmix64_mix(self.0) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn random_vpls(n: usize, u: &mut U) -> Vec<Vpl> {
    (0..n)
        .map(|k| {
            let p = DVec3::new(u.f(), u.f(), u.f()) * 4.0;
            let i = [u.f(), u.f() * 2.0, u.f() * 0.5];
            if k % 3 == 0 {
                Vpl::point(p, i)
            } else {
                let n = DVec3::new(u.f() - 0.5, u.f() - 0.5, -1.0 - u.f());
                Vpl::oriented(p, n, i)
            }
        })
        .collect()
}

/// Leaves below a node.
fn leaves(tree: &LightTree, id: u32, out: &mut Vec<u32>) {
    match tree.node(id).children {
        None => out.push(tree.node(id).vpl),
        Some([a, b]) => {
            leaves(tree, a, out);
            leaves(tree, b, out);
        }
    }
}

#[test]
fn every_node_sums_boxes_and_cones_its_vpls() {
    let mut u = U(9);
    let vpls = random_vpls(37, &mut u);
    let tree = LightTree::new(vpls.clone()).unwrap();
    assert_eq!(tree.nodes().len(), 2 * 37 - 1);
    let mut all = Vec::new();
    leaves(&tree, tree.root(), &mut all);
    all.sort_unstable();
    assert_eq!(
        all,
        (0..37).collect::<Vec<u32>>(),
        "each VPL in exactly one leaf"
    );
    for id in 0..tree.nodes().len() as u32 {
        let node = tree.node(id);
        let mut below = Vec::new();
        leaves(&tree, id, &mut below);
        let sum: f64 = below
            .iter()
            .map(|&k| vpls[k as usize].scalar_intensity())
            .sum();
        assert!((node.intensity - sum).abs() <= 1e-12 * sum);
        assert!(below.contains(&node.representative));
        for &k in &below {
            let v = &vpls[k as usize];
            assert!(node.bbox.contains(v.position));
            match (node.cone, v.normal) {
                (Some(c), Some(n)) => assert!(c.contains(n), "cone {c:?} misses {n:?}"),
                (Some(_), None) => panic!("a node holding a point light has a cone"),
                (None, _) => assert!(below.iter().any(|&j| vpls[j as usize].normal.is_none())),
            }
        }
        // Median split: the two children differ by at most one VPL.
        if let Some([a, b]) = node.children {
            let (mut la, mut lb) = (Vec::new(), Vec::new());
            leaves(&tree, a, &mut la);
            leaves(&tree, b, &mut lb);
            assert!(la.len().abs_diff(lb.len()) <= 1);
        }
    }
}

#[test]
fn cones_of_oriented_vpls_contain_all_normals() {
    let mut u = U(4);
    for trial in 0..50 {
        let spread = 0.1 + 2.0 * u.f();
        let vpls: Vec<Vpl> = (0..20)
            .map(|_| {
                let n = DVec3::new((u.f() - 0.5) * spread, (u.f() - 0.5) * spread, 1.0);
                Vpl::oriented(DVec3::new(u.f(), u.f(), u.f()), n, [1.0; 3])
            })
            .collect();
        let tree = LightTree::new(vpls.clone()).unwrap();
        let cone = tree.node(0).cone.expect("all oriented");
        for v in &vpls {
            assert!(cone.contains(v.normal.unwrap()), "trial {trial}");
        }
        assert!(cone.half_angle <= std::f64::consts::PI);
    }
}

/// The descent picks each VPL with probability I(y)/I_root and reports that probability; the
/// empirical frequencies agree within 5 binomial standard errors.
#[test]
fn sampling_is_proportional_to_intensity() {
    let mut u = U(2);
    let mut vpls = random_vpls(12, &mut u);
    vpls[5].intensity = [0.0; 3]; // never picked
    let tree = LightTree::new(vpls.clone()).unwrap();
    let total: f64 = vpls.iter().map(|v| v.scalar_intensity()).sum();
    let n = 300_000;
    let mut count = vec![0usize; vpls.len()];
    for _ in 0..n {
        let (k, p) = tree.sample(tree.root(), u.f());
        let want = vpls[k as usize].scalar_intensity() / total;
        assert!((p - want).abs() <= 1e-12, "reported p {p} vs {want}");
        count[k as usize] += 1;
    }
    assert_eq!(count[5], 0);
    for (k, v) in vpls.iter().enumerate() {
        let pk = v.scalar_intensity() / total;
        let se = (pk * (1.0 - pk) / n as f64).sqrt().max(1e-12);
        let got = count[k] as f64 / n as f64;
        assert!((got - pk).abs() < 5.0 * se, "VPL {k}: {got} vs {pk}");
    }
}

#[test]
fn emission_follows_the_kind() {
    let p = Vpl::point(DVec3::ZERO, [1.0; 3]);
    assert_eq!(p.kind(), VplKind::Point);
    assert_eq!(p.emission_cos(DVec3::NEG_Z), 1.0);
    let o = Vpl::oriented(DVec3::ZERO, DVec3::new(0.0, 0.0, -2.0), [1.0; 3]);
    assert_eq!(o.kind(), VplKind::Oriented);
    assert_eq!(o.emission_cos(DVec3::NEG_Z), 1.0);
    assert_eq!(o.emission_cos(DVec3::Z), 0.0);
    let d = DVec3::new(1.0, 0.0, -1.0).normalize();
    assert!((o.emission_cos(d) - std::f64::consts::FRAC_1_SQRT_2).abs() < 1e-15);
}
