//! Irradiance clusters: longest-edge halving conserves area, refinement tiles the mesh (no
//! triangle lost or counted twice), the split cap holds, and sampling is uniform in area
//! (Eq. 7).

use glam::DVec3;
use sss_manylight::*;
use std::collections::HashMap;

/// A deterministic uniform stream (SplitMix64) for the tests.
struct U(u64);
impl U {
    fn f(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        (sss_util::splitmix64_mix(self.0) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn cross_area(t: &Triangle) -> f64 {
    0.5 * (t.v[1] - t.v[0]).cross(t.v[2] - t.v[0]).length()
}

#[test]
fn halving_conserves_area_and_halves_the_longest_edge() {
    let mut u = U(1);
    for _ in 0..1000 {
        let p: [DVec3; 3] = std::array::from_fn(|_| DVec3::new(u.f(), u.f(), u.f()) * 3.0 - 1.0);
        let t = Triangle::new(p[0], p[1], p[2]);
        assert!((t.area - cross_area(&t)).abs() <= 1e-15 * (1.0 + t.area));
        let [a, b] = t.halve();
        // Stored areas: exactly half each, so sums are exact.
        assert_eq!(a.area + b.area, t.area);
        // Geometric areas agree with the stored ones to rounding.
        for h in [a, b] {
            assert!((cross_area(&h) - 0.5 * t.area).abs() <= 1e-12 * (1.0 + t.area));
            // Same orientation as the parent.
            let n = (h.v[1] - h.v[0]).cross(h.v[2] - h.v[0]);
            assert!(n.dot(t.normal) >= 0.0);
        }
        // The cut is the midpoint of the longest edge: it is a vertex of both halves, and the
        // longest edge of each half is no longer than the parent's.
        let longest = |t: &Triangle| {
            (0..3)
                .map(|i| (t.v[(i + 1) % 3] - t.v[i]).length())
                .fold(0.0, f64::max)
        };
        let l = longest(&t);
        let mids: Vec<DVec3> = (0..3).map(|i| 0.5 * (t.v[i] + t.v[(i + 1) % 3])).collect();
        let m = a.v[1];
        assert_eq!(m, b.v[0]);
        let k = mids
            .iter()
            .position(|&x| x == m)
            .expect("cut at an edge midpoint");
        assert!(((t.v[(k + 1) % 3] - t.v[k]).length() - l).abs() <= 1e-15 * l);
        assert!(longest(&a) <= l * (1.0 + 1e-15) && longest(&b) <= l * (1.0 + 1e-15));
    }
}

/// A random frontier of clusters that starts at the root; a random member is repeatedly
/// replaced by its two halves (BVH children or triangle halves). Every frontier must tile the
/// mesh: its areas sum to the mesh area, and per original triangle the split pieces sum to its
/// area. A second frontier splitting the same clusters gets the same arena ids (splits are
/// reused, never duplicated).
#[test]
fn refinement_never_loses_or_double_counts_a_triangle() {
    // A 6 × 6 grid of a bumpy height field: 72 triangles of different areas.
    let n = 6;
    let mut pos = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f64 / n as f64, j as f64 / n as f64);
            pos.push(DVec3::new(x, y, 0.2 * (5.0 * x).sin() * (3.0 * y).cos()));
        }
    }
    let mut tris = Vec::new();
    for j in 0..n as u32 {
        for i in 0..n as u32 {
            let a = j * (n as u32 + 1) + i;
            let w = n as u32 + 1;
            tris.push([a, a + 1, a + w + 1]);
            tris.push([a, a + w + 1, a + w]);
        }
    }
    let tree = TriangleClusterTree::new(&pos, &tris).unwrap();
    let total: f64 = tree.triangles().iter().map(|t| t.area).sum();
    assert!((tree.area() - total).abs() <= 1e-12 * total);

    let mut refs = Refinements::new(10_000);
    let mut origin: HashMap<IcId, u32> = HashMap::new(); // arena cluster -> mesh triangle
    let mut frontier = vec![tree.root()];
    let mut u = U(7);
    let mut first_splits: Vec<(IcId, [IcId; 2])> = Vec::new();
    for step in 0..3000 {
        let k = (u.f() * frontier.len() as f64) as usize;
        let id = frontier.swap_remove(k);
        let [a, b] = refs.split(&tree, id).expect("under the cap");
        if let IcId::Base(nid) = id
            && tree.nodes()[nid as usize].children.is_none()
        {
            origin.insert(a, tree.nodes()[nid as usize].triangle);
            origin.insert(b, tree.nodes()[nid as usize].triangle);
        }
        if let IcId::Split(_) = id {
            let o = origin[&id];
            origin.insert(a, o);
            origin.insert(b, o);
        }
        first_splits.push((id, [a, b]));
        frontier.push(a);
        frontier.push(b);
        if step % 100 == 0 || step == 2999 {
            let sum: f64 = frontier.iter().map(|&c| refs.area(&tree, c)).sum();
            assert!(
                (sum - total).abs() <= 1e-12 * total,
                "step {step}: {sum} vs {total}"
            );
            // Per mesh triangle: the pieces of the frontier that came from it.
            let mut per = vec![0.0; tree.triangles().len()];
            for &c in &frontier {
                match c {
                    IcId::Split(_) => per[origin[&c] as usize] += refs.area(&tree, c),
                    IcId::Base(nid) => {
                        // Every mesh triangle below this BVH node, whole.
                        let mut stack = vec![nid];
                        while let Some(m) = stack.pop() {
                            let node = tree.nodes()[m as usize];
                            match node.children {
                                Some([x, y]) => stack.extend([x, y]),
                                None => per[node.triangle as usize] += node.area,
                            }
                        }
                    }
                }
            }
            for (t, got) in tree.triangles().iter().zip(&per) {
                assert!(
                    (got - t.area).abs() <= 1e-12 * t.area,
                    "{got} vs {}",
                    t.area
                );
            }
        }
    }
    assert!(
        refs.splits() > 1000,
        "the test reaches deep splits: {}",
        refs.splits()
    );
    // Splitting again (as another triplet of the same pixel would) reuses the same halves.
    let before = refs.splits();
    for (id, halves) in &first_splits {
        assert_eq!(refs.split(&tree, *id), Some(*halves));
    }
    assert_eq!(refs.splits(), before);
    // Arena triangles' boxes contain their vertices and lie in their parents' boxes.
    for node in refs.nodes() {
        for v in node.triangle.v {
            assert!(node.bbox.contains(v));
        }
    }
}

#[test]
fn the_split_cap_holds_and_is_counted() {
    let pos = [DVec3::ZERO, DVec3::X, DVec3::Y];
    let tree = TriangleClusterTree::new(&pos, &[[0, 1, 2]]).unwrap();
    let mut refs = Refinements::new(3);
    let [a, _] = refs.split(&tree, tree.root()).unwrap();
    let [c, _] = refs.split(&tree, a).unwrap();
    let [e, f] = refs.split(&tree, c).unwrap();
    assert_eq!(refs.splits(), 3);
    assert!(!refs.can_split(&tree, e));
    assert_eq!(refs.split(&tree, e), None);
    assert_eq!(refs.split(&tree, f), None);
    assert_eq!(refs.cap_hits(), 2);
    // Already-split clusters still return their halves at the cap.
    assert!(refs.can_split(&tree, a));
    assert!(refs.split(&tree, a).is_some());
    assert_eq!(refs.nodes().len(), 6);
    refs.clear();
    assert_eq!(
        (refs.splits(), refs.cap_hits(), refs.nodes().len()),
        (0, 0, 0)
    );
}

/// Eq. 7: points fall in each triangle in proportion to its area, and uniformly inside it
/// (the fraction in the half of a triangle cut at an edge midpoint is ½). Binomial margins of 5
/// standard errors.
#[test]
fn cluster_sampling_is_uniform_in_area() {
    // Three triangles of areas 0.5, 0.75 and 0.25 (all in z = 0).
    let pos = [
        DVec3::ZERO,
        DVec3::X,
        DVec3::Y,
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(2.0, 1.5, 0.0),
        DVec3::new(3.0, 0.0, 0.0),
        DVec3::new(3.0, 0.5, 0.0),
        DVec3::new(4.0, 0.0, 0.0),
    ];
    let tris = [[0, 1, 2], [3, 5, 4], [5, 7, 6]];
    let tree = TriangleClusterTree::new(&pos, &tris).unwrap();
    let areas: Vec<f64> = tree.triangles().iter().map(|t| t.area).collect();
    assert_eq!(areas, vec![0.5, 0.75, 0.25]);
    let refs = Refinements::new(0);
    let mut u = U(3);
    let n = 200_000;
    let mut count = [0usize; 3];
    let mut left_half = 0usize;
    for _ in 0..n {
        let at = refs.sample(&tree, tree.root(), [u.f(), u.f(), u.f()]);
        let (p, nrm) = (at.position, at.normal);
        assert_eq!(nrm.z.abs(), 1.0);
        let k = if p.x <= 1.0 {
            0
        } else if p.x <= 3.0 {
            1
        } else {
            2
        };
        count[k] += 1;
        if k == 0 && p.x < p.y {
            left_half += 1;
        }
    }
    let total = 1.5;
    for k in 0..3 {
        let pk = areas[k] / total;
        let se = (pk * (1.0 - pk) / n as f64).sqrt();
        let got = count[k] as f64 / n as f64;
        assert!((got - pk).abs() < 5.0 * se, "triangle {k}: {got} vs {pk}");
    }
    // Inside triangle 0 the line x = y splits the area in two halves.
    let se = (0.25 / count[0] as f64).sqrt();
    let got = left_half as f64 / count[0] as f64;
    assert!((got - 0.5).abs() < 5.0 * se, "{got}");
}

#[test]
fn bad_meshes_are_errors() {
    let p = [DVec3::ZERO, DVec3::X, DVec3::Y];
    assert!(TriangleClusterTree::new(&p, &[]).is_err());
    assert!(TriangleClusterTree::new(&p, &[[0, 1, 3]]).is_err());
    assert!(TriangleClusterTree::new(&p, &[[0, 0, 1]]).is_err()); // zero area
    assert!(TriangleClusterTree::new(&[DVec3::NAN, DVec3::X, DVec3::Y], &[[0, 1, 2]]).is_err());
    assert!(ShadingTree::new(vec![]).is_err());
    let sp = ShadingPoint {
        position: DVec3::ZERO,
        normal: DVec3::Z,
        weight: -1.0,
    };
    assert!(ShadingTree::new(vec![sp]).is_err());
    assert!(LightTree::new(vec![]).is_err());
    assert!(LightTree::new(vec![Vpl::point(DVec3::ZERO, [1.0, -1.0, 0.0])]).is_err());
    assert!(LightTree::new(vec![Vpl::oriented(DVec3::ZERO, DVec3::ZERO, [1.0; 3])]).is_err());
}

/// The barycentric coordinates of `p` (in the triangle's plane) in `t`, from sub-triangle
/// areas: independent of the sampler's parameterisation.
fn barycentric_of(t: &Triangle, p: DVec3) -> [f64; 3] {
    let area = |a: DVec3, b: DVec3, c: DVec3| 0.5 * (b - a).cross(c - a).length();
    let whole = area(t.v[0], t.v[1], t.v[2]);
    [
        area(p, t.v[1], t.v[2]) / whole,
        area(t.v[0], p, t.v[2]) / whole,
        area(t.v[0], t.v[1], p) / whole,
    ]
}

/// Phong's normal at `p`: the vertex normals blended by `p`'s barycentric coordinates,
/// normalised.
fn phong(t: &Triangle, p: DVec3) -> DVec3 {
    let b = barycentric_of(t, p);
    (b[0] * t.vertex_normals[0] + b[1] * t.vertex_normals[1] + b[2] * t.vertex_normals[2])
        .normalize()
}

/// A sample's shading normal is the vertex normals blended at the sampled point; halving keeps
/// every point's normal (the halves blend as their parent did), and every normal lies in the
/// triangle's cone. A flat triangle keeps its one normal and a cone of half-angle 0.
#[test]
fn shading_normals_interpolate_and_survive_halving() {
    let mut u = U(7);
    for trial in 0..300 {
        let p: [DVec3; 3] = std::array::from_fn(|_| DVec3::new(u.f(), u.f(), u.f()) * 2.0 - 1.0);
        let flat = Triangle::new(p[0], p[1], p[2]);
        // Vertex normals tilted up to about 60° from the face normal.
        let n: [DVec3; 3] = std::array::from_fn(|_| {
            (flat.normal + DVec3::new(u.f(), u.f(), u.f()) * 1.6 - 0.8).normalize()
        });
        let t = Triangle::with_normals(p[0], p[1], p[2], n);
        assert_eq!(t.area, flat.area);
        assert_eq!(t.normal, flat.normal);
        let cone = t.cone().unwrap();
        // Follow a random chain of halvings; at each level, sample the current piece and
        // compare its shading normal with the ORIGINAL triangle's blend at that point.
        let mut piece = t;
        for level in 0..8 {
            for _ in 0..8 {
                let s = piece.sample_with_normals(u.f(), u.f());
                assert_eq!(s.geometric, t.normal);
                let want = phong(&t, s.position);
                assert!(
                    s.normal.distance(want) < 1e-9,
                    "trial {trial} level {level}: {} vs {want}",
                    s.normal
                );
                assert!((s.normal.length() - 1.0).abs() < 1e-12);
                let angle = s.normal.dot(cone.axis).clamp(-1.0, 1.0).acos();
                assert!(
                    angle <= cone.half_angle + 1e-9,
                    "trial {trial}: outside the cone"
                );
                let piece_cone = piece.cone().unwrap();
                let a = s.normal.dot(piece_cone.axis).clamp(-1.0, 1.0).acos();
                assert!(
                    a <= piece_cone.half_angle + 1e-9,
                    "outside the piece's cone"
                );
            }
            piece = piece.halve()[(u.f() * 2.0) as usize];
        }
        let fc = flat.cone().unwrap();
        assert_eq!((fc.axis, fc.half_angle), (flat.normal, 0.0));
        let s = flat.sample_with_normals(u.f(), u.f());
        assert_eq!(s.normal, flat.normal);
        for h in flat.halve() {
            assert_eq!(h.vertex_normals, [flat.normal; 3]);
        }
    }
    // Two vertex normals equal and the third not: still blended (not the shared one).
    let (a, b, c) = (DVec3::ZERO, DVec3::X, DVec3::Y);
    let up = DVec3::Z;
    let tilted = DVec3::new(0.6, 0.0, 0.8);
    for n in [[up, up, tilted], [tilted, up, up], [up, tilted, up]] {
        let t = Triangle::with_normals(a, b, c, n);
        let mut u = U(5);
        for _ in 0..50 {
            let s = t.sample_with_normals(u.f(), u.f());
            assert!(s.normal.distance(phong(&t, s.position)) < 1e-9, "{n:?}");
            let cone = t.cone().unwrap();
            let angle = s.normal.dot(cone.axis).clamp(-1.0, 1.0).acos();
            assert!(angle <= cone.half_angle + 1e-9, "{n:?}: outside the cone");
        }
    }
    // Vertex normals leaning together 50° off the face normal: the cone is theirs alone, not
    // widened to the face normal (which no interpolated normal reaches).
    let lean = |dx: f64, dy: f64| DVec3::new(0.766 + dx, dy, 0.643).normalize();
    let t = Triangle::with_normals(a, b, c, [lean(0.0, 0.0), lean(0.02, 0.0), lean(0.0, 0.02)]);
    let cone = t.cone().unwrap();
    assert!(cone.half_angle < 0.05, "{}", cone.half_angle);
    assert!(cone.axis.angle_between(up) > 0.8);
    // The point-only sampler gives the same points as the sampler with normals, inside the
    // triangle.
    let t = Triangle::with_normals(a, b, c, [up, up, tilted]);
    let mut u = U(6);
    for _ in 0..100 {
        let (u1, u2) = (u.f(), u.f());
        let p = t.sample(u1, u2);
        assert_eq!(p, t.sample_with_normals(u1, u2).position);
        let bary = barycentric_of(&t, p);
        assert!(
            (bary.iter().sum::<f64>() - 1.0).abs() < 1e-12,
            "{p} outside"
        );
    }
    // Zero and non-finite vertex normals fall back to the face normal.
    let t = Triangle::with_normals(
        DVec3::ZERO,
        DVec3::X,
        DVec3::Y,
        [DVec3::ZERO, DVec3::NAN, DVec3::new(0.0, 0.0, 2.0)],
    );
    assert_eq!(t.vertex_normals, [DVec3::Z; 3]);
}

/// A tree built with a mesh's vertex normals samples Phong's normal: on an octahedron with
/// radial vertex normals the blended normal at a point is the point's own direction.
#[test]
fn tree_samples_carry_the_mesh_normals() {
    let pos = [
        DVec3::X,
        -DVec3::X,
        DVec3::Y,
        -DVec3::Y,
        DVec3::Z,
        -DVec3::Z,
    ];
    let tris = [
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];
    let tree = TriangleClusterTree::with_normals(&pos, &pos, &tris).unwrap();
    let flat = TriangleClusterTree::new(&pos, &tris).unwrap();
    let mut refs = Refinements::new(64);
    let mut u = U(11);
    let mut max_tilt: f64 = 0.0;
    for _ in 0..2000 {
        let w = [u.f(), u.f(), u.f()];
        let s = tree.sample_uniform(w);
        assert!(s.normal.distance(s.position.normalize()) < 1e-12);
        let f = flat.sample_uniform(w);
        assert_eq!(f.position, s.position, "the same point either way");
        assert_eq!(f.normal, f.geometric);
        assert_eq!(s.geometric, f.geometric);
        max_tilt = max_tilt.max(s.normal.angle_between(s.geometric));
        // The same through a refined cluster.
        let root = tree.root();
        let [a, _] = refs.split(&tree, root).unwrap();
        let r = refs.sample(&tree, a, [u.f(), u.f(), u.f()]);
        assert!(r.normal.distance(r.position.normalize()) < 1e-12);
        let cone = refs.cone(&tree, a).unwrap();
        assert!(r.normal.angle_between(cone.axis) <= cone.half_angle + 1e-9);
    }
    // Near a vertex the radial normal is 54.7° from the face normal.
    assert!(max_tilt > 0.8, "{max_tilt}");
    let e = TriangleClusterTree::with_normals(&pos, &pos[..5], &tris).unwrap_err();
    assert!(
        format!("{e:?}").contains("5 normals for 6 vertices"),
        "{e:?}"
    );
}
