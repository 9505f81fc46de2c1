//! Ray casting against whole scenes: [`SceneGeometry::closest_hit`] (which visits the objects
//! nearest bounding box first) against a brute-force loop over every triangle of every object
//! in index order, including exact ties between objects; and [`GBuffer::new`] (cast in runs of
//! pixels, then flattened) against a per-pixel loop over the camera's samples, for several
//! thread counts.

use super::common::{diffuse, scene_of};
use glam::DVec3;
use rand::{RngExt, SeedableRng};
use rand_pcg::Pcg64Mcg;
use sss_hierarchy::intersect_triangle;
use sss_render::camera::{CameraFrame, pixel_samples};
use sss_render::gbuffer::{GBuffer, GSample};
use sss_render::geometry::SceneGeometry;
use sss_render::scene::{Camera, Mesh, Scene};

/// A mesh of the given triangles (each with its own three vertices) and random unit normals.
fn soup(tris: &[[DVec3; 3]], rng: &mut Pcg64Mcg) -> Mesh {
    let positions: Vec<DVec3> = tris.iter().flatten().copied().collect();
    let normals = positions
        .iter()
        .map(|_| {
            DVec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(0.2..1.0),
            )
            .normalize()
        })
        .collect();
    let triangles = (0..tris.len() as u32)
        .map(|i| [3 * i, 3 * i + 1, 3 * i + 2])
        .collect();
    Mesh {
        positions,
        normals,
        triangles,
    }
}

/// An n × n grid in the plane y = `y`, ±`half` in x and z.
fn grid(y: f64, half: f64, n: u32) -> Vec<[DVec3; 3]> {
    let p = |i: u32, j: u32| {
        DVec3::new(
            -half + 2.0 * half * i as f64 / n as f64,
            y,
            -half + 2.0 * half * j as f64 / n as f64,
        )
    };
    let mut out = Vec::new();
    for j in 0..n {
        for i in 0..n {
            out.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
            out.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
        }
    }
    out
}

/// The triangle shared by objects 1 and 3 (exact ties between objects).
const SHARED: [DVec3; 3] = [
    DVec3::new(-0.5, -0.5, 0.3),
    DVec3::new(0.6, -0.4, 0.3),
    DVec3::new(0.0, 0.7, 0.3),
];

/// Five overlapping objects: a random soup, the shared triangle alone (object 1), a ground grid
/// cutting through everything, the shared triangle again with a far-off sliver that stretches
/// its box towards +z (object 3: rays from +z enter its box first, so the nearest-box order
/// visits it before object 1 and the tie rule is exercised), and a second, coplanar grid.
fn scene(width: u32, height: u32, spp: u32) -> Scene {
    let mut rng = Pcg64Mcg::seed_from_u64(17);
    let mut tris = Vec::new();
    for _ in 0..200 {
        let c = DVec3::new(
            rng.random_range(-1.5..1.5),
            rng.random_range(-1.0..1.5),
            rng.random_range(-1.5..1.5),
        );
        let mut v = || {
            c + DVec3::new(
                rng.random_range(-0.3..0.3),
                rng.random_range(-0.3..0.3),
                rng.random_range(-0.3..0.3),
            )
        };
        tris.push([v(), v(), v()]);
    }
    let sliver = [
        DVec3::new(2.5, 2.5, 4.0),
        DVec3::new(2.6, 2.5, 4.0),
        DVec3::new(2.5, 2.6, 4.1),
    ];
    let meshes = vec![
        soup(&tris, &mut rng),
        soup(&[SHARED], &mut rng),
        soup(&grid(-0.2, 3.0, 5), &mut rng),
        soup(&[sliver, SHARED], &mut rng),
        soup(&grid(-0.2, 2.0, 3), &mut rng),
    ];
    scene_of(
        meshes,
        diffuse(),
        Vec::new(),
        Camera {
            position: DVec3::new(0.4, 2.5, 6.0),
            target: DVec3::new(0.0, 0.0, 0.0),
            up: DVec3::Y,
            vfov_deg: 45.0,
            width,
            height,
            pixel_samples: spp,
        },
    )
}

/// A brute-force hit: (object, triangle, t, u, v).
type BruteHit = (u32, u32, f64, f64, f64);

/// Brute force: every triangle of every object (or of object `only`) in index order, keeping
/// strictly closer hits only, so exact ties go to the lowest object, then the lowest triangle.
fn brute(
    s: &Scene,
    only: Option<usize>,
    o: DVec3,
    d: DVec3,
    t_min: f64,
    t_max: f64,
) -> Option<BruteHit> {
    let mut best: Option<BruteHit> = None;
    for (i, obj) in s.objects.iter().enumerate() {
        if only.is_some_and(|k| k != i) {
            continue;
        }
        let m = &obj.mesh;
        for (k, t) in m.triangles.iter().enumerate() {
            let tri = t.map(|v| m.positions[v as usize]);
            let Some((t, u, v)) = intersect_triangle(o, d, &tri) else {
                continue;
            };
            if t > t_min && t < t_max && best.is_none_or(|b| t < b.2) {
                best = Some((i as u32, k as u32, t, u, v));
            }
        }
    }
    best
}

#[test]
fn scene_closest_hit_equals_brute_force_over_all_objects() {
    let s = scene(8, 8, 1);
    let geom = SceneGeometry::new(&s);
    let mut rng = Pcg64Mcg::seed_from_u64(5);
    let (mut hits, mut ties) = (0, 0);
    for r in 0..20000 {
        let o = DVec3::new(
            rng.random_range(-3.0..3.0),
            rng.random_range(-1.0..3.0),
            rng.random_range(2.0..6.0),
        );
        // Aim at a random point, every fourth ray at the shared triangle.
        let target = if r % 4 == 0 {
            let (a, b) = (rng.random_range(0.0..0.5), rng.random_range(0.0..0.5));
            SHARED[0] + a * (SHARED[1] - SHARED[0]) + b * (SHARED[2] - SHARED[0])
        } else {
            DVec3::new(
                rng.random_range(-3.0..3.0),
                rng.random_range(-1.5..2.0),
                rng.random_range(-3.0..3.0),
            )
        };
        let d = (target - o) * rng.random_range(0.5..2.0);
        let t_min = if r % 3 == 0 {
            rng.random_range(0.0..0.5)
        } else {
            0.0
        };
        let t_max = if r % 5 == 0 {
            rng.random_range(0.5..1.5)
        } else {
            f64::INFINITY
        };
        let got = geom.closest_hit(o, d, t_min, t_max);
        let want = brute(&s, None, o, d, t_min, t_max);
        match (got, want) {
            (None, None) => {}
            (Some(g), Some((obj, tri, t, u, v))) => {
                assert_eq!((g.object, g.triangle, g.t), (obj, tri, t), "ray {r}");
                // The hit point is the barycentric point, on the ray.
                let m = &s.objects[obj as usize].mesh;
                let [a, b, c] = m.triangles[tri as usize].map(|i| m.positions[i as usize]);
                let p = a * (1.0 - u - v) + b * u + c * v;
                assert!((g.p - p).length() < 1e-12, "ray {r}");
                assert!((g.p - (o + d * t)).length() < 1e-9, "ray {r}");
                // Unit geometric normal, perpendicular to the triangle's edges.
                assert!((g.ng.length() - 1.0).abs() < 1e-12, "ray {r}");
                assert!(g.ng.dot(b - a).abs() < 1e-12 && g.ng.dot(c - a).abs() < 1e-12);
                assert!((g.n.length() - 1.0).abs() < 1e-12, "ray {r}");
                hits += 1;
                if obj == 1 {
                    // The same triangle of object 3 is hit at exactly the same t. Object 3's
                    // box contains object 1's flat one (z = 0.3) and every ray starts at
                    // z >= 2, so object 3 was visited first and lost the tie by its index.
                    ties += 1;
                    let on3 = geom.closest_hit_on(3, o, d, t_min, t_max).expect("tie");
                    assert_eq!(on3.t, t);
                }
            }
            (g, w) => panic!("ray {r}: got {g:?}, brute force {w:?}"),
        }
        // The single-object query agrees with brute force restricted to that object.
        let k = r % s.objects.len() as u32;
        let want_on = brute(&s, Some(k as usize), o, d, t_min, t_max).map(|h| (k, h.1, h.2));
        let got_on = geom
            .closest_hit_on(k, o, d, t_min, t_max)
            .map(|h| (h.object, h.triangle, h.t));
        assert_eq!(got_on, want_on, "ray {r} on object {k}");
    }
    assert!(hits > 10000, "{hits} hits");
    assert!(ties > 1000, "{ties} ties");
}

/// The G-buffer, built by the reference definition: pixel by pixel, sample by sample.
fn reference_gbuffer(s: &Scene, geom: &SceneGeometry, seed: u64) -> (Vec<GSample>, Vec<u32>) {
    let cam = &s.camera;
    let frame = CameraFrame::new(cam);
    let mut samples = Vec::new();
    let mut offsets = vec![0];
    for i in 0..cam.width as u64 * cam.height as u64 {
        let (px, py) = ((i % cam.width as u64) as u32, (i / cam.width as u64) as u32);
        for (k, (x, y)) in pixel_samples(seed, i, px, py, cam.pixel_samples)
            .into_iter()
            .enumerate()
        {
            let d = frame.direction(x, y);
            if let Some(h) = geom.closest_hit(frame.origin(), d, 0.0, f64::INFINITY) {
                samples.push(GSample {
                    pixel: i as u32,
                    index: k as u32,
                    object: h.object,
                    triangle: h.triangle,
                    p: h.p,
                    n: h.n,
                    ng: h.ng,
                    wo: -d,
                    distance: h.t,
                    footprint: h.t * frame.pixel_angle(),
                });
            }
        }
        offsets.push(samples.len() as u32);
    }
    (samples, offsets)
}

#[test]
fn gbuffer_equals_the_per_pixel_definition_for_any_thread_count() {
    // 97 × 61 pixels are several runs of the parallel cast, the last one partial; some pixels
    // see the sky, some only part of their samples hit.
    for spp in [1, 3] {
        let s = scene(97, 61, spp);
        let geom = SceneGeometry::new(&s);
        let (samples, offsets) = reference_gbuffer(&s, &geom, 9);
        let misses = offsets.len() - 1 - offsets.windows(2).filter(|w| w[1] > w[0]).count();
        assert!(misses > 100, "{misses} pixels with no hit");
        assert!(samples.len() > 2000);
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let g = pool.install(|| GBuffer::new(&s, &geom, 9));
            assert_eq!((g.width, g.height, g.samples_per_pixel), (97, 61, spp));
            assert_eq!(g.offsets, offsets, "spp {spp}, {threads} threads");
            assert_eq!(g.samples, samples, "spp {spp}, {threads} threads");
            assert_eq!(g.pixels(), 97 * 61);
            assert_eq!(
                g.pixel(5000),
                &samples[offsets[5000] as usize..offsets[5001] as usize]
            );
        }
    }
}
