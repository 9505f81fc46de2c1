//! End-to-end tests of the two references on scenes built in code: the flat-slab closed form,
//! agreement of `pathtrace` with `exact`, determinism, and the irradiance samples' invariants.

use super::common::{scene_with, square, translucent, uv_sphere};
use glam::DVec3;
use sss_bssrdf::fresnel::ft_dielectric;
use sss_bssrdf::{Medium, ModelKind, fresnel_normalization, make_model};
use sss_render::geometry::SceneGeometry;
use sss_render::integrators::Integrator;
use sss_render::integrators::exact::Exact;
use sss_render::integrators::pathtrace::PathTrace;
use sss_render::irradiance::{self, IrradianceSettings};
use sss_render::progress::NoProgress;
use sss_render::scene::{Camera, Light, Scene};
use sss_render::{RenderOutput, RenderSettings, render};
use std::f64::consts::PI;

/// A large flat slab under a distant light, seen from above: away from the edges the exact
/// sum equals the closed form F_t(η, cos θ_o)/(cπ) · E_t · R_d,total (a semi-infinite
/// half-space's diffuse reflectance; pbrt Eq. 11.6-11.7).
#[test]
fn flat_slab_matches_closed_form() {
    // marble: 1/σ'_t ≈ 0.4 mm (red) → scene unit = mm; a 40 mm square.
    let units_per_mm = 1.0;
    let material = translucent(ModelKind::BetterDipole, "marble", units_per_mm);
    let e0 = [2.0, 1.0, 0.5];
    let camera = Camera {
        position: DVec3::new(0.0, 50.0, 0.0),
        target: DVec3::ZERO,
        up: DVec3::Z,
        vfov_deg: 2.0,
        width: 5,
        height: 5,
        pixel_samples: 1,
    };
    let scene = scene_with(
        square(40.0, 8),
        material,
        vec![Light::Directional {
            direction: DVec3::NEG_Y,
            irradiance: e0,
        }],
        camera,
    );
    let exact = Exact {
        irradiance: IrradianceSettings {
            spacing_mfp: 0.25,
            max_samples: 1_000_000,
            light_samples: 1,
            bounces: 0,
        },
    };
    let out = render(&scene, &exact, &RenderSettings::default(), &NoProgress).unwrap();
    let medium = Medium::preset("marble").unwrap();
    let model = make_model(ModelKind::BetterDipole, &medium);
    let eta = medium.eta();
    let centre = 2 * 5 + 2;
    // The camera looks straight down: cos θ_o ≈ 1 at the centre pixel.
    let ft = ft_dielectric(1.0, eta);
    for c in 0..3 {
        let closed = ft / (fresnel_normalization(eta) * PI)
            * ft
            * e0[c]
            * model.total_diffuse_reflectance(c);
        let got = out.subsurface[centre][c];
        let rel = (got - closed).abs() / closed;
        eprintln!("slab channel {c}: exact {got:.6e}, closed form {closed:.6e}, rel {rel:.2e}");
        assert!(
            rel < 0.01,
            "channel {c}: exact {got} vs closed form {closed} ({rel:.4})"
        );
    }
}

fn sphere_scene(model: ModelKind) -> Scene {
    let camera = Camera {
        position: DVec3::new(0.0, 0.0, 4.0),
        target: DVec3::ZERO,
        up: DVec3::Y,
        vfov_deg: 30.0,
        width: 24,
        height: 24,
        pixel_samples: 1,
    };
    // skin1, 1 scene unit = 10 mm: 1/σ'_t ≈ 0.13 (red) scene units on a unit sphere.
    scene_with(
        uv_sphere(DVec3::ZERO, 1.0, 48, 96),
        translucent(model, "skin1", 0.1),
        vec![Light::Point {
            position: DVec3::new(3.0, 2.0, 3.0),
            intensity: [10.0; 3],
        }],
        camera,
    )
}

fn pixels(out: &RenderOutput) -> Vec<usize> {
    out.translucent_pixels()
}

/// The path tracer converges to the integral the exact point sum approximates: with fine
/// irradiance samples the two agree within the path tracer's stated error.
#[test]
fn pathtrace_agrees_with_exact_on_a_sphere() {
    let scene = sphere_scene(ModelKind::BetterDipole);
    let exact = render(
        &scene,
        &Exact {
            irradiance: IrradianceSettings {
                spacing_mfp: 0.25,
                max_samples: 400_000,
                light_samples: 1,
                bounces: 0,
            },
        },
        &RenderSettings::default(),
        &NoProgress,
    )
    .unwrap();
    let pt = render(
        &scene,
        &PathTrace {
            spp: 256,
            ..PathTrace::default()
        },
        &RenderSettings {
            seed: 7,
            ..RenderSettings::default()
        },
        &NoProgress,
    )
    .unwrap();
    let px = pixels(&exact);
    assert!(px.len() > 100, "the sphere covers {} pixels", px.len());
    let se = pt
        .std_error
        .as_ref()
        .expect("path tracer reports standard errors");
    // Aggregate: the image means agree within 3 standard errors of the path tracer's mean
    // plus 1 % for the point sum's discretisation.
    for c in 0..3 {
        let m_ex: f64 = px.iter().map(|&i| exact.subsurface[i][c]).sum::<f64>() / px.len() as f64;
        let m_pt: f64 = px.iter().map(|&i| pt.subsurface[i][c]).sum::<f64>() / px.len() as f64;
        let se_mean =
            (px.iter().map(|&i| se[i][c] * se[i][c]).sum::<f64>()).sqrt() / px.len() as f64;
        eprintln!(
            "sphere channel {c}: exact mean {m_ex:.6e}, pathtrace {m_pt:.6e} ± {se_mean:.2e}"
        );
        assert!(
            (m_ex - m_pt).abs() <= 3.0 * se_mean + 0.01 * m_ex,
            "channel {c}: exact mean {m_ex}, pathtrace mean {m_pt} ± {se_mean}"
        );
    }
    // Per pixel: nearly all pixels within 3 of their own standard errors (+1 % discretisation).
    let ok = px
        .iter()
        .filter(|&&i| {
            (0..3).all(|c| {
                (exact.subsurface[i][c] - pt.subsurface[i][c]).abs()
                    <= 3.0 * se[i][c] + 0.01 * exact.subsurface[i][c]
            })
        })
        .count();
    let frac = ok as f64 / px.len() as f64;
    eprintln!("{ok} of {} pixels within 3 SE (+1 %)", px.len());
    assert!(frac > 0.95, "only {frac:.3} of pixels agree within 3 SE");
}

/// Same seed, same bits, whatever the thread count; another seed changes the noise.
#[test]
fn renders_are_deterministic() {
    let scene = sphere_scene(ModelKind::StandardDipole);
    let methods: [&dyn Integrator; 2] = [
        &Exact::default(),
        &PathTrace {
            spp: 2,
            ..PathTrace::default()
        },
    ];
    for method in methods {
        let s = RenderSettings {
            seed: 3,
            ..RenderSettings::default()
        };
        let run = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| render(&scene, method, &s, &NoProgress).unwrap())
        };
        let (a, b) = (run(1), run(2));
        assert_eq!(a.subsurface, b.subsurface, "{}", method.name());
        assert_eq!(a.total, b.total, "{}", method.name());
        assert!(
            a.subsurface
                .iter()
                .flatten()
                .all(|v| v.is_finite() && *v >= 0.0)
        );
        if method.name() == "pathtrace" {
            let other = render(
                &scene,
                method,
                &RenderSettings {
                    seed: 4,
                    ..s.clone()
                },
                &NoProgress,
            )
            .unwrap();
            assert_ne!(a.subsurface, other.subsurface);
        }
    }
}

/// Irradiance samples: areas sum to the object's area, spacing holds, and a sample facing a
/// point light gets F_t · I cos θ / d².
#[test]
fn irradiance_samples_cover_the_object() {
    let scene = sphere_scene(ModelKind::BetterDipole);
    let geom = SceneGeometry::new(&scene);
    let settings = IrradianceSettings {
        spacing_mfp: 0.5,
        max_samples: 50_000,
        light_samples: 1,
        bounces: 0,
    };
    let samples = irradiance::compute(&scene, &geom, &[0], &settings, 1);
    assert_eq!(samples.len(), 1);
    let s = &samples[0];
    let mesh = &scene.objects[0].mesh;
    let area: f64 = mesh
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum();
    let sum: f64 = s.samples.iter().map(|x| x.area).sum();
    assert!(
        (sum - area).abs() < 1e-9 * area,
        "areas sum to {sum}, mesh area {area}"
    );
    let medium = Medium::preset("skin1").unwrap();
    let mfp = (0..3)
        .map(|c| 1.0 / medium.sigma_t_reduced(c))
        .fold(f64::INFINITY, f64::min);
    assert!(
        s.spacing >= 0.5 * mfp * 0.1 * (1.0 - 1e-12),
        "spacing {}",
        s.spacing
    );
    // Brute-force minimum distance over a subset.
    let n = s.samples.len().min(1500);
    for i in 0..n {
        for j in 0..i {
            let d = (s.samples[i].position - s.samples[j].position).length();
            assert!(
                d >= s.spacing * (1.0 - 1e-9),
                "samples {i} and {j} are {d} apart"
            );
        }
    }
    // Closed-form irradiance for unshadowed samples facing the light.
    let light = DVec3::new(3.0, 2.0, 3.0);
    let mut checked = 0;
    for x in &s.samples {
        let d = light - x.position;
        let wi = d.normalize();
        let cos = x.normal.dot(wi);
        if cos > 0.3 {
            let expect = ft_dielectric(cos, medium.eta()) * 10.0 * cos / d.length_squared();
            assert!(
                (x.irradiance[0] - expect).abs() < 1e-9 * expect,
                "{} vs {expect}",
                x.irradiance[0]
            );
            checked += 1;
        }
    }
    assert!(checked > 100);
}

/// The film's alpha is the silhouette: against the test rasteriser (edge functions at pixel
/// centres, no code shared with the ray caster), 1 wherever a pixel and its eight neighbours
/// are covered, 0 wherever none of them is, and its sum the covered area to within the
/// silhouette's edge pixels. The translucent coverage is the alpha of the translucent object
/// alone. Built-in `picnic` scene (translucent and opaque objects on a ground plane, sky
/// above), 16 samples a pixel.
#[test]
fn alpha_is_the_silhouette_the_rasteriser_sees() {
    use super::common::rasterizer::rasterize;
    let mut s = super::common::scene("picnic", 80, 60);
    s.camera.pixel_samples = 16;
    let m = sss_render::integrators::build("separable", &Default::default()).unwrap();
    let out = render(&s, m.as_ref(), &RenderSettings::default(), &NoProgress).unwrap();
    let raster = rasterize(&s);
    let (w, h) = (80usize, 60usize);
    let hit = |x: i64, y: i64| {
        (0..w as i64).contains(&x)
            && (0..h as i64).contains(&y)
            && raster.ids[y as usize * w + x as usize].is_some()
    };
    let (mut inside, mut outside, mut edge) = (0, 0, 0);
    let mut covered = 0usize;
    for y in 0..h as i64 {
        for x in 0..w as i64 {
            let a = out.alpha[y as usize * w + x as usize];
            assert!((0.0..=1.0).contains(&a), "alpha {a} at ({x}, {y})");
            let around: Vec<bool> = (-1..=1)
                .flat_map(|dy| (-1..=1).map(move |dx| (dx, dy)))
                .map(|(dx, dy)| hit(x + dx, y + dy))
                .collect();
            covered += hit(x, y) as usize;
            if around.iter().all(|&b| b) {
                assert_eq!(a, 1.0, "inside the silhouette at ({x}, {y})");
                inside += 1;
            } else if around.iter().all(|&b| !b) {
                assert_eq!(a, 0.0, "outside the silhouette at ({x}, {y})");
                outside += 1;
            } else {
                edge += 1;
            }
            let c = out.coverage[y as usize * w + x as usize];
            assert!(
                c <= a,
                "translucent coverage {c} above alpha {a} at ({x}, {y})"
            );
        }
    }
    println!("{inside} inside, {outside} outside, {edge} on edges");
    assert!(
        inside > 300 && outside > 300,
        "{inside} inside, {outside} outside"
    );
    let sum: f64 = out.alpha.iter().map(|&a| a as f64).sum();
    // Each edge pixel's alpha is a 16-sample estimate: the sum errs by far less than the
    // number of edge pixels (pixel-centre rasterising errs by about half of each).
    assert!(
        (sum - covered as f64).abs() < 0.1 * edge as f64,
        "alpha sums to {sum}, the rasteriser covers {covered} pixels ({edge} on edges)"
    );
    // Opaque pixels: alpha 1, translucent coverage 0.
    let opaque = (0..w * h)
        .filter(|&i| out.alpha[i] == 1.0 && out.coverage[i] == 0.0)
        .count();
    assert!(opaque > 100, "{opaque} wholly opaque pixels");
}

/// A large object seen close up is sampled only where its profile reaches a visible point: a
/// 200 mm skin1 sphere (better dipole), an 8×6 view of a patch of it. Against samples over
/// the whole sphere at the same spacing (2 mean free paths, so the whole sphere fits under
/// the cap): every whole-sphere sample within the reach of a G-buffer point has a kept sample
/// within twice the spacing (brute force over all pairs); the exact point sums differ by no
/// more than two whole-sphere placements (seeds 1 and 2) differ from each other (measured:
/// 3.3 % against 3.1 % relative RMS on a 12×9 view); the samples left out are at least 80 %
/// of the whole sphere's, and the count the renderer reports is the whole sphere's less the
/// kept to within 10 %.
#[test]
fn irradiance_samples_only_within_reach_of_what_is_seen() {
    use rayon::prelude::*;
    use sss_render::frame::Frame;
    use sss_render::integrators::exact::shade;
    let camera = Camera {
        position: DVec3::new(0.0, 0.0, 1.1),
        target: DVec3::ZERO,
        up: DVec3::Y,
        vfov_deg: 12.0,
        width: 8,
        height: 6,
        pixel_samples: 1,
    };
    // 1 scene unit = 200 mm: a 100 mm radius; skin1's reach (all but 10⁻⁶ of R_d) is about
    // 45 mm = 0.22 units, the patch seen about 0.13 units across.
    let scene = scene_with(
        uv_sphere(DVec3::ZERO, 0.5, 96, 192),
        translucent(ModelKind::BetterDipole, "skin1", 0.005),
        vec![Light::Point {
            position: DVec3::new(1.0, 1.0, 3.0),
            intensity: [10.0; 3],
        }],
        camera,
    );
    let settings = IrradianceSettings {
        spacing_mfp: 2.0,
        max_samples: 200_000,
        light_samples: 1,
        bounces: 0,
    };
    let frame = Frame::prepare(&scene, 1);
    let sh = frame.shading_of(0).unwrap();
    let shaded = frame.shaded_points();
    let reach = shaded[0].reach;
    assert!(
        reach > 0.1 && reach < 0.5,
        "skin1's reach {reach} scene units"
    );
    let whole = irradiance::compute(&scene, &frame.geom, &[0], &settings, 1);
    let other = irradiance::compute(&scene, &frame.geom, &[0], &settings, 2);
    let kept = irradiance::compute_for(&scene, &frame.geom, &[0], &settings, 1, &shaded);
    let (whole, other, kept) = (&whole[0], &other[0], &kept[0]);
    assert!(!whole.capped(&settings) && !kept.capped(&settings));
    assert_eq!(whole.left_out, 0);
    assert!(
        kept.samples.len() * 5 < whole.samples.len(),
        "kept {} of {}",
        kept.samples.len(),
        whole.samples.len()
    );
    let dropped = (whole.samples.len() - kept.samples.len()) as f64;
    assert!(
        (kept.left_out as f64 - dropped).abs() < 0.1 * dropped,
        "reported {} left out, {dropped} fewer than the whole sphere's",
        kept.left_out
    );
    // Coverage: every whole-sphere sample within reach of a seen point has a kept neighbour.
    let seen: Vec<DVec3> = frame.gbuffer.samples.iter().map(|g| g.p).collect();
    assert!(seen.len() == 48, "{} G-buffer samples", seen.len());
    let mut near = 0;
    for s in &whole.samples {
        if seen.iter().any(|p| (s.position - *p).length() <= reach) {
            near += 1;
            let covered = kept
                .samples
                .iter()
                .any(|k| (k.position - s.position).length() <= 2.0 * kept.spacing);
            assert!(covered, "no kept sample near {} (within reach)", s.position);
        }
    }
    assert!(near > 100, "{near} samples within reach");
    // The sums: culling changes them by no more than another placement does.
    let sums = |s: &irradiance::ObjectSamples| -> Vec<[f64; 3]> {
        frame
            .gbuffer
            .samples
            .par_iter()
            .map(|g| shade(g, sh, s))
            .collect()
    };
    let (a, b, c) = (sums(whole), sums(other), sums(kept));
    let rms = |x: &[[f64; 3]], y: &[[f64; 3]]| {
        let (mut num, mut den) = (0.0, 0.0);
        for (p, q) in x.iter().zip(y) {
            for ch in 0..3 {
                num += (p[ch] - q[ch]).powi(2);
                den += q[ch].powi(2);
            }
        }
        (num / den.max(1e-300)).sqrt()
    };
    let (placement, culling) = (rms(&b, &a), rms(&c, &a));
    println!("relative RMS: another placement {placement:.4}, culled {culling:.4}");
    assert!(placement > 0.0 && placement < 0.05, "placement {placement}");
    assert!(
        culling <= 2.0 * placement,
        "culled differs by {culling}, another placement by {placement}"
    );
}
