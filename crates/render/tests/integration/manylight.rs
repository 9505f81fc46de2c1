//! The `manylight` integrator against an independent brute force over the same light, its
//! caps and refusals, and the VPLs it is built on (closed forms of their total power).

use crate::common::brute_force_sphere;
use glam::DVec3;
use sss_manylight::StudentT;
use sss_render::frame::Frame;
use sss_render::integrators::vpl::vpls::{DISTANT_FACTOR, scene_vpls};
use sss_render::integrators::{self, MethodOptions};
use sss_render::progress::NoProgress;
use sss_render::scene::{LoadOptions, Scene, builtin};
use sss_render::{RenderSettings, render};
use sss_scene::Light;
use std::f64::consts::PI;

const LUM: [f64; 3] = [0.2126, 0.7152, 0.0722];

fn lum(c: [f64; 3]) -> f64 {
    LUM[0] * c[0] + LUM[1] * c[1] + LUM[2] * c[2]
}

fn scene(name: &str, w: u32, h: u32) -> Scene {
    let mut s = builtin(name, &LoadOptions::default()).unwrap();
    s.camera.width = w;
    s.camera.height = h;
    s
}

#[test]
fn agrees_with_brute_force_within_its_intervals() {
    // 24 × 18 pixels, 2 samples each: about 130 lit pixels of the skin sphere.
    let mut s = scene("sphere", 24, 18);
    s.camera.pixel_samples = 2;
    let settings = RenderSettings::default();
    let frame = Frame::prepare(&s, settings.seed);
    let reference = brute_force_sphere(&s, &frame);
    let eps = 0.02;
    let m = integrators::build("manylight", &MethodOptions::new().with("rel-error", eps)).unwrap();
    let out = render(&s, m.as_ref(), &settings, &NoProgress).unwrap();
    let se = out.std_error.as_ref().unwrap();
    let triplets = out.layer("triplets").unwrap();
    let t = StudentT::new(0.95).unwrap();
    let (mut n, mut inside, mut rel_sum) = (0usize, 0usize, 0.0);
    for i in 0..reference.len() {
        let r = lum(reference[i]);
        if r <= 0.0 {
            continue;
        }
        let v = lum(out.subsurface[i]);
        let j = triplets[i][0] as usize;
        assert!(j >= 8, "pixel {i}: {j} triplets");
        let delta = t.quantile(j) * lum(se[i]);
        n += 1;
        rel_sum += (v - r).abs() / r;
        // 0.3 % of slack for the brute force's own quadrature error.
        if (v - r).abs() <= delta + 3e-3 * r {
            inside += 1;
        }
    }
    let frac = inside as f64 / n as f64;
    let mean_rel = rel_sum / n as f64;
    eprintln!("{n} pixels, {frac:.3} inside ΔI, mean relative error {mean_rel:.4}");
    assert!(n > 80, "{n} lit pixels");
    // α = 95 %: at least 85 % of pixels inside (a binomial of 100+ pixels at p = 0.95 falls
    // below 0.85 with probability < 1e-4), and the mean error well under ε.
    assert!(frac >= 0.85, "{frac} of pixels inside their intervals");
    assert!(mean_rel < eps, "mean relative error {mean_rel}");
}

/// The luminance image mean of `img` over the pixels where `reference` is positive, and (with
/// `se`) its standard error from the per-pixel ones.
fn image_mean(img: &[[f64; 3]], se: Option<&[[f64; 3]]>, reference: &[[f64; 3]]) -> (f64, f64) {
    let (mut sum, mut var, mut n) = (0.0, 0.0, 0usize);
    for i in 0..img.len() {
        if lum(reference[i]) > 0.0 {
            sum += lum(img[i]);
            if let Some(se) = se {
                var += lum(se[i]).powi(2);
            }
            n += 1;
        }
    }
    (sum / n as f64, var.sqrt() / n as f64)
}

/// An icosahedron (20 flat faces, radial vertex normals, skin1 with the standard dipole) lit
/// from the side. Irradiance is taken against the interpolated shading normal by `exact` and
/// `pathtrace`; an estimator that took the flat faces' own normals had an image mean 7.6 %
/// above a 1 024-sample path trace here (1.5 % on the 80-face icosphere, 1 % on a scanned
/// 100 000-triangle dragon). `manylight` must agree with the path tracer (a method sharing no
/// code with it: probe rays, light sampling at the hit) on the image mean, and its intervals
/// must hold over the pixels.
#[test]
fn agrees_with_the_path_tracer_on_a_faceted_mesh() {
    let text = r#"
[camera]
position = [0.0, 0.6, 5.0]
target = [0.0, 0.0, 0.0]
fov = 30.0
resolution = [32, 24]
pixel_samples = 2

[[lights]]
type = "point"
position = [4.0, 1.0, 1.0]
intensity = 100.0

[materials.skin]
type = "translucent"
model = "standard-dipole"
preset = "skin1"
units_per_mm = 0.05

[[objects]]
name = "ball"
material = "skin"
shape = "sphere"
radius = 1.0
subdivisions = 0
"#;
    let s =
        sss_render::scene::load_str(text, "faceted.toml", None, &LoadOptions::default()).unwrap();
    let settings = RenderSettings::default();
    let pt = integrators::build("pathtrace", &MethodOptions::new().with("spp", 4096)).unwrap();
    let reference = render(&s, pt.as_ref(), &settings, &NoProgress).unwrap();
    let pt_se = reference.std_error.as_ref().unwrap();
    let eps = 0.01;
    let m = integrators::build("manylight", &MethodOptions::new().with("rel-error", eps)).unwrap();
    let out = render(&s, m.as_ref(), &settings, &NoProgress).unwrap();
    let se = out.std_error.as_ref().unwrap();
    let (ref_mean, ref_se) = image_mean(&reference.subsurface, Some(pt_se), &reference.subsurface);
    let (mean, _) = image_mean(&out.subsurface, None, &reference.subsurface);
    let ratio = mean / ref_mean;
    eprintln!(
        "image mean / path tracer's: {ratio:.5} (its relative SE {:.5})",
        ref_se / ref_mean
    );
    // The path tracer's mean is known to 0.12 % here (1 SE, 4 096 samples); 0.5 % is 4 of its
    // standard errors, with manylight's own ε-level noise averaged over the image.
    assert!(
        ref_se / ref_mean < 1.5e-3,
        "reference too noisy: {}",
        ref_se / ref_mean
    );
    assert!((ratio - 1.0).abs() < 5e-3, "image mean ratio {ratio}");

    // Per pixel: inside the Student-t interval widened by 3 of the path tracer's own SE.
    let triplets = out.layer("triplets").unwrap();
    let t = StudentT::new(0.95).unwrap();
    let (mut n, mut inside) = (0usize, 0usize);
    for i in 0..out.subsurface.len() {
        let r = lum(reference.subsurface[i]);
        if r <= 0.0 {
            continue;
        }
        let j = triplets[i][0] as usize;
        let delta = t.quantile(j.max(2)) * lum(se[i]);
        let width = (delta * delta + (3.0 * lum(pt_se[i])).powi(2)).sqrt();
        n += 1;
        inside += ((lum(out.subsurface[i]) - r).abs() <= width) as usize;
    }
    let frac = inside as f64 / n as f64;
    eprintln!("{n} pixels, {frac:.3} inside");
    assert!(n > 100, "{n} lit pixels");
    assert!(frac >= 0.85, "{frac} of pixels inside their intervals");

    // The baselines take cos θ_i at their irradiance points against the same shading normals:
    // EELC over 256 importance-sampled points per shading point (its point set's noise,
    // averaged over the image, is about 0.2 %) agrees with the path tracer as `manylight`
    // does. With the points' flat-triangle normals it was 7 % high here.
    let eelc = integrators::build(
        "eelc",
        &MethodOptions::new()
            .with("rel-error", 0.01)
            .with("irradiance-points", 256),
    )
    .unwrap();
    let out = render(&s, eelc.as_ref(), &settings, &NoProgress).unwrap();
    let (mean, _) = image_mean(&out.subsurface, None, &reference.subsurface);
    let ratio = mean / ref_mean;
    eprintln!("eelc image mean / path tracer's: {ratio:.5}");
    assert!((ratio - 1.0).abs() < 1e-2, "eelc image mean ratio {ratio}");
}

#[test]
fn caps_are_reported_and_hold() {
    let s = scene("sphere", 12, 9);
    let m = integrators::build(
        "manylight",
        &MethodOptions::new()
            .with("rel-error", 0)
            .with("max-triplets", 40),
    )
    .unwrap();
    let out = render(&s, m.as_ref(), &RenderSettings::default(), &NoProgress).unwrap();
    let stat = |n: &str| out.stats.iter().find(|s| s.name == n).unwrap().value;
    let estimates = stat("pixel_estimates");
    assert!(estimates > 20.0, "{estimates}");
    // ε = 0 never converges: every lit estimate stops at the cap of 40 triplets.
    assert_eq!(stat("pixels_converged"), 0.0);
    assert_eq!(
        stat("pixels_triplet_cap") + stat("pixels_zero") + stat("pixels_exact"),
        estimates
    );
    assert!(stat("pixels_triplet_cap") >= 0.9 * estimates);
    let layer = out.layer("triplets").unwrap();
    assert!(layer.iter().all(|p| p[0] <= 40.0), "cap held");
    assert!(stat("mean_triplets") <= 40.0 && stat("mean_triplets") >= 30.0);
    assert!(
        out.warnings.iter().any(|w| w.contains("triplet cap")),
        "{:?}",
        out.warnings
    );
}

#[test]
fn directional_dipole_and_bad_options_are_clear_errors() {
    let s = scene("picnic", 16, 12);
    let m = integrators::build("manylight", &MethodOptions::new()).unwrap();
    let err = render(&s, m.as_ref(), &RenderSettings::default(), &NoProgress)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("`apple`") && err.contains("directional"),
        "{err}"
    );
    for (k, v) in [
        ("rel-error", "-1"),
        ("alpha", "1"),
        ("selection", "random"),
        ("vpls", "0"),
        ("max-triplets", "0"),
    ] {
        let e = integrators::build("manylight", &MethodOptions::new().with(k, v))
            .err()
            .unwrap_or_else(|| panic!("--{k} {v} accepted"))
            .to_string();
        assert!(e.contains(&format!("--{k}")), "{e}");
    }
}

#[test]
fn vpls_carry_the_lights_power() {
    // Quad: Σ I_k = L·A (each VPL is L·A/N along the normal), every VPL on the quad.
    let s = scene("backlit", 8, 6);
    let Some(&Light::Quad {
        corner,
        edge_u,
        edge_v,
        radiance,
    }) = s.lights.iter().find(|l| matches!(l, Light::Quad { .. }))
    else {
        panic!("backlit has a quad light")
    };
    let vpls = scene_vpls(&s, 100, 1, DVec3::ZERO, 1.0).unwrap();
    let quad: Vec<_> = vpls.iter().filter(|v| v.normal.is_some()).collect();
    assert_eq!(quad.len(), 100);
    let area = edge_u.cross(edge_v).length();
    let n = edge_u.cross(edge_v) / area;
    for (c, l) in radiance.iter().enumerate() {
        let sum: f64 = quad.iter().map(|v| v.intensity[c]).sum();
        assert!((sum - l * area).abs() <= 1e-12 * l * area);
    }
    let (gu, gv) = (edge_u.length_squared(), edge_v.length_squared());
    for v in &quad {
        let d = v.position - corner;
        assert!(d.dot(n).abs() < 1e-9);
        let (a, b) = (d.dot(edge_u) / gu, d.dot(edge_v) / gv);
        assert!((0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b));
        assert!((v.normal.unwrap() - n).length() < 1e-12);
    }
    // 100 = 10 × 10 strata: each cell of a 10 × 10 grid holds exactly one VPL.
    let mut cells = [0u32; 100];
    for v in &quad {
        let d = v.position - corner;
        let (a, b) = (d.dot(edge_u) / gu, d.dot(edge_v) / gv);
        cells[((a * 10.0) as usize).min(9) + 10 * ((b * 10.0) as usize).min(9)] += 1;
    }
    assert!(cells.iter().all(|&c| c == 1));

    // Environment (picnic): N distant VPLs, Σ I_k/D² = 4π L; their irradiance on an upward
    // plane (open sky) is π L up to the sampling error: per VPL 4π L max(0, y) has standard
    // deviation 1.29 π L, so over 4096 VPLs the relative error is 2 % per σ; 6 % is 3σ.
    let p = scene("picnic", 8, 6);
    let Some(&Light::Environment { radiance }) = p
        .lights
        .iter()
        .find(|l| matches!(l, Light::Environment { .. }))
    else {
        panic!("picnic has an environment light")
    };
    let vpls = scene_vpls(&p, 4096, 3, DVec3::ZERO, 2.0).unwrap();
    let far = DISTANT_FACTOR * 2.0;
    let env: Vec<_> = vpls
        .iter()
        .filter(|v| (v.position.length() - far).abs() < 1e-6 * far)
        .collect();
    assert_eq!(env.len(), 4096);
    let total: f64 = env.iter().map(|v| v.intensity[1]).sum::<f64>() / (far * far);
    assert!((total - 4.0 * PI * radiance[1]).abs() < 1e-9 * total);
    let e_up: f64 = env
        .iter()
        .map(|v| v.intensity[1] / (far * far) * (v.position.normalize().y).max(0.0))
        .sum();
    let rel = (e_up - PI * radiance[1]).abs() / (PI * radiance[1]);
    assert!(rel < 0.06, "irradiance on an upward plane off by {rel}");
    // The point light is one VPL of its intensity.
    assert_eq!(vpls.len(), 4097);
}

#[test]
fn every_radial_model_and_light_kind_of_picnic_renders() {
    // Picnic with the apple's directional dipole swapped for the better dipole: standard
    // dipole, PBD (a tabulated profile: its monotonicity check must pass) and better dipole,
    // under a point and an environment light; every value finite and ≥ 0, every object lit.
    let mut s = scene("picnic", 32, 24);
    for m in &mut s.materials {
        if let sss_scene::MaterialKind::Translucent(t) = &mut m.kind
            && t.model == sss_bssrdf::ModelKind::DirectionalDipole
        {
            t.model = sss_bssrdf::ModelKind::BetterDipole;
        }
    }
    let m = integrators::build(
        "manylight",
        &MethodOptions::new().with("rel-error", 0.1).with("vpls", 64),
    )
    .unwrap();
    let out = render(&s, m.as_ref(), &RenderSettings::default(), &NoProgress).unwrap();
    let stat = |n: &str| out.stats.iter().find(|s| s.name == n).unwrap().value;
    assert_eq!(stat("vpls"), 65.0, "1 point + 64 environment VPLs");
    let frame = Frame::prepare(&s, 1);
    let mut lit = vec![false; s.objects.len()];
    for g in &frame.gbuffer.samples {
        let v = out.subsurface[g.pixel as usize];
        assert!(v.iter().all(|x| x.is_finite() && *x >= 0.0), "{v:?}");
        if frame.shading_of(g.object).is_some() && v.iter().any(|x| *x > 0.0) {
            lit[g.object as usize] = true;
        }
    }
    for &o in &frame.visible {
        assert!(
            lit[o as usize],
            "object {} unlit",
            s.objects[o as usize].name
        );
    }
    assert!(stat("pixels_converged") > 0.5 * stat("pixel_estimates"));
}

/// `shade_pixels` gives a pixel subset exactly the values a full render gives those pixels
/// (each pixel's estimate is seeded by its own index), in the order asked, and refuses a pixel
/// past the image.
#[test]
fn shading_a_subset_equals_the_full_render_there() {
    let mut s = scene("sphere", 20, 15);
    s.camera.pixel_samples = 2;
    let settings = RenderSettings::default();
    let m = integrators::manylight::ManyLight {
        eps: 0.05,
        ..Default::default()
    };
    let full = render(&s, &m, &settings, &NoProgress).unwrap();
    let frame = Frame::prepare(&s, settings.seed);
    let lit: Vec<usize> = (0..full.subsurface.len())
        .filter(|&i| lum(full.subsurface[i]) > 0.0)
        .collect();
    assert!(lit.len() > 40, "{} lit pixels", lit.len());
    // Every fifth lit pixel, in reverse order, plus one black pixel.
    let black = (0..full.subsurface.len())
        .find(|&i| lum(full.subsurface[i]) == 0.0)
        .unwrap();
    let mut pick: Vec<usize> = lit.iter().copied().step_by(5).rev().collect();
    pick.push(black);
    let sub = m.shade_pixels(&frame, &pick).unwrap();
    assert_eq!(sub.len(), pick.len());
    let se = full.std_error.as_ref().unwrap();
    for (r, &i) in sub.iter().zip(&pick) {
        assert_eq!(r.subsurface, full.subsurface[i], "pixel {i}");
        assert_eq!(r.std_error, se[i], "pixel {i}");
    }
    assert_eq!(sub.last().unwrap().subsurface, [0.0; 3]);
    let n = full.subsurface.len();
    let err = m.shade_pixels(&frame, &[n]).unwrap_err().to_string();
    assert!(err.contains("past the image"), "{err}");
}

/// The baselines' `shade_pixels` give a pixel subset exactly the values and standard errors a
/// full render gives those pixels, bit for bit with 1 and 2 threads, with importance-sampled
/// and uniform points, in the order asked; they refuse a pixel past the image. Another
/// `stream` draws other points (the values change), and `vpl_seed` equal to the frame's seed
/// changes nothing.
#[test]
fn baseline_subsets_equal_the_full_render_there() {
    use sss_render::integrators::eelc::Eelc;
    use sss_render::integrators::manylight::PixelResult;
    use sss_render::integrators::mdlc::Mdlc;
    use sss_render::integrators::vpl::gather_points::PointOptions;
    let mut s = scene("sphere", 20, 15);
    s.camera.pixel_samples = 2;
    let settings = RenderSettings::default();
    let frame = Frame::prepare(&s, settings.seed);
    let pool = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    };
    for uniform in [false, true] {
        let points = PointOptions {
            irradiance_points: 48,
            uniform,
            ..PointOptions::default()
        };
        let mdlc = Mdlc { eps: 0.05, points };
        let eelc = Eelc {
            eps: 0.05,
            points,
            ..Eelc::default()
        };
        type Subset<'a> = Box<dyn Fn(&[usize], PointOptions) -> Vec<PixelResult> + Sync + 'a>;
        let methods: [(&str, &dyn sss_render::integrators::Integrator, Subset<'_>); 2] = [
            (
                "mdlc",
                &mdlc,
                Box::new(|p: &[usize], points| {
                    Mdlc { points, ..mdlc }.shade_pixels(&frame, p).unwrap()
                }),
            ),
            (
                "eelc",
                &eelc,
                Box::new(|p: &[usize], points| {
                    Eelc { points, ..eelc }.shade_pixels(&frame, p).unwrap()
                }),
            ),
        ];
        for (name, m, subset) in &methods {
            let full = render(&s, *m, &settings, &NoProgress).unwrap();
            let lit: Vec<usize> = (0..full.subsurface.len())
                .filter(|&i| lum(full.subsurface[i]) > 0.0)
                .collect();
            assert!(lit.len() > 40, "{name}: {} lit pixels", lit.len());
            let black = (0..full.subsurface.len())
                .find(|&i| lum(full.subsurface[i]) == 0.0)
                .unwrap();
            let mut pick: Vec<usize> = lit.iter().copied().step_by(5).rev().collect();
            pick.push(black);
            let pairs = full.layer("pairs").unwrap();
            for threads in [1, 2] {
                let sub = pool(threads).install(|| subset(&pick, points));
                assert_eq!(sub.len(), pick.len());
                for (r, &i) in sub.iter().zip(&pick) {
                    let what = format!("{name} uniform={uniform} threads={threads} pixel {i}");
                    let bits = |v: [f64; 3]| v.map(f64::to_bits);
                    assert_eq!(bits(r.subsurface), bits(full.subsurface[i]), "{what}");
                    match &full.std_error {
                        Some(se) => assert_eq!(bits(r.std_error), bits(se[i]), "{what}"),
                        None => assert_eq!(r.std_error, [0.0; 3], "{what}"),
                    }
                    assert_eq!(r.triplets, pairs[i][0], "{what}");
                }
                assert_eq!(sub.last().unwrap().subsurface, [0.0; 3]);
                assert!(sub.iter().any(|r| r.triplets > 1.0), "{name}");
            }
            // Another stream: other points, so other values on the lit pixels; the VPLs drawn
            // from the frame's own seed: the same bits.
            let other = subset(
                &pick,
                PointOptions {
                    stream: 7,
                    ..points
                },
            );
            let same = subset(
                &pick,
                PointOptions {
                    vpl_seed: Some(settings.seed),
                    ..points
                },
            );
            let differ = other
                .iter()
                .zip(&pick)
                .filter(|(r, i)| r.subsurface != full.subsurface[**i])
                .count();
            assert!(
                differ >= pick.len() - 2,
                "{name}: {differ} of {} differ",
                pick.len()
            );
            for (r, &i) in same.iter().zip(&pick) {
                assert_eq!(r.subsurface, full.subsurface[i], "{name} vpl_seed");
            }
            let n = full.subsurface.len();
            let err = Mdlc { points, ..mdlc }
                .shade_pixels(&frame, &[n])
                .unwrap_err()
                .to_string();
            assert!(
                err.contains("past the image") && err.contains("mdlc"),
                "{err}"
            );
            let err = Eelc { points, ..eelc }
                .shade_pixels(&frame, &[0, n + 3])
                .unwrap_err()
                .to_string();
            assert!(
                err.contains("past the image") && err.contains("eelc"),
                "{err}"
            );
        }
    }
}

/// A square diffuse floor of side 2a under a light, and a small skin sphere standing on it.
fn floor_scene(light: &str, albedo: f64) -> Scene {
    let text = format!(
        r#"
[camera]
position = [0.0, 3.0, 6.0]
target = [0.0, 0.0, 0.0]
fov = 40.0
resolution = [24, 18]

{light}

[materials.floor]
type = "diffuse"
albedo = {albedo}

[materials.skin]
type = "translucent"
model = "better-dipole"
preset = "skin1"
units_per_mm = 0.05

[[objects]]
name = "floor"
material = "floor"
shape = "plane"
size = [4.0, 4.0]

[[objects]]
name = "ball"
material = "skin"
shape = "sphere"
radius = 0.3
transform = {{ translate = [1.2, 0.3, 0.0] }}
"#
    );
    sss_render::scene::load_str(&text, "floor.toml", None, &LoadOptions::default()).unwrap()
}

/// One-bounce VPLs carry the reflected power: under a point light of intensity I at height h
/// over a square of side 2b, a fraction Ω/4π of the 4πI emitted lands on it (Ω = 4 arcsin(b²/
/// (b² + h²)), the solid angle of the square from a point on its axis), of which the floor
/// (albedo ρ) re-emits ρ; a cosine VPL of intensity I_v emits π I_v. Under a directional light
/// of irradiance E straight down the floor receives E (2b)². Every VPL lies on the floor's top
/// (none on the translucent ball, none underneath) and faces up.
#[test]
fn bounce_vpls_carry_the_reflected_power() {
    let (h, b, rho, intensity) = (2.0f64, 2.0f64, 0.6, 10.0);
    let point = floor_scene(
        &format!(
            "[[lights]]\ntype = \"point\"\nposition = [0.0, {h}, 0.0]\nintensity = {intensity}\n"
        ),
        rho,
    );
    let dir = floor_scene(
        "[[lights]]\ntype = \"directional\"\ndirection = [0.0, -1.0, 0.0]\nirradiance = 3.0\n",
        rho,
    );
    let omega = 4.0 * (b * b / (b * b + h * h)).asin();
    // The ball (radius 0.3 at (1.2, 0.3, 0)) shadows the floor: from the point light it covers
    // the solid angle 2π(1 − cos α), sin α = r / distance, and its shadow lies on the floor;
    // under the directional light it hides a disk of area πr².
    let (r, c) = (0.3f64, DVec3::new(1.2, 0.3, 0.0));
    let sin_a = r / c.distance(DVec3::new(0.0, h, 0.0));
    let omega_ball = 2.0 * PI * (1.0 - (1.0 - sin_a * sin_a).sqrt());
    let paths = 40_000u32;
    for (s, want) in [
        (&point, rho * intensity * (omega - omega_ball)),
        (&dir, rho * 3.0 * ((2.0 * b) * (2.0 * b) - PI * r * r)),
    ] {
        let frame = Frame::prepare(s, 1);
        let (lo, hi) = (0..s.objects.len() as u32)
            .filter_map(|o| frame.geom.bounds(o))
            .fold(
                (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
                |(a, c), (p, q)| (a.min(p), c.max(q)),
            );
        let (center, radius) = (0.5 * (lo + hi), 0.5 * (hi - lo).length());
        let v = sss_render::integrators::vpl::vpls::bounce_vpls(
            s,
            &frame.geom,
            paths,
            7,
            center,
            radius,
        );
        let total: f64 = v.iter().map(|x| PI * x.intensity[0]).sum();
        // Each path lands with probability p; the sum is (power / N) × hits.
        let power = sss_render::integrators::vpl::vpls::light_power(&s.lights[0], radius)[0];
        let p = (want / rho / power).min(1.0);
        let se = want * ((1.0 - p) / (p * f64::from(paths))).sqrt();
        assert!(
            (total - want).abs() < 4.0 * se + 1e-9 * want,
            "reflected power {total} vs {want} ± {se}"
        );
        assert!(v.len() > 1000, "{} VPLs", v.len());
        for x in &v {
            assert!(
                x.position.y > 0.0 && x.position.y < 1e-3,
                "{:?}",
                x.position
            );
            assert_eq!(x.normal, Some(DVec3::Y));
        }
    }
    // Off by default; on, the integrator's light tree holds them and the image brightens.
    let m0 =
        integrators::build("manylight", &MethodOptions::new().with("rel-error", 0.05)).unwrap();
    let m1 = integrators::build(
        "manylight",
        &MethodOptions::new()
            .with("rel-error", 0.05)
            .with("bounce-vpls", 2000),
    )
    .unwrap();
    let settings = RenderSettings::default();
    let o0 = render(&point, m0.as_ref(), &settings, &NoProgress).unwrap();
    let o1 = render(&point, m1.as_ref(), &settings, &NoProgress).unwrap();
    let stat =
        |o: &sss_render::RenderOutput| o.stats.iter().find(|s| s.name == "vpls").unwrap().value;
    assert_eq!(stat(&o0), 1.0);
    // 2000 paths, of which Ω/4π ≈ 16 % land on the floor: about 330 VPLs.
    assert!((250.0..420.0).contains(&stat(&o1)), "{}", stat(&o1));
    let sum = |o: &sss_render::RenderOutput| o.subsurface.iter().map(|p| lum(*p)).sum::<f64>();
    assert!(sum(&o1) > 1.02 * sum(&o0), "{} vs {}", sum(&o1), sum(&o0));
    assert!(m1.describe().contains("one bounce"));
}

// ---------------------------------------------------------------------------------------------
// The baselines `mdlc` and `eelc` (same VPLs, light tree, weights and G clamp as `manylight`).
// ---------------------------------------------------------------------------------------------

/// The relative difference Σ(b − m)/Σm of the luminances over the pixels where m > 0, and its
/// standard error √n · sd(b − m)/Σm (pixels are independent: each has its own irradiance
/// points), and the pixel count.
fn relative_difference(b: &[[f64; 3]], m: &[[f64; 3]]) -> (f64, f64, usize) {
    let (d, sm): (Vec<f64>, Vec<f64>) = b
        .iter()
        .zip(m)
        .filter(|(_, m)| lum(**m) > 0.0)
        .map(|(b, m)| (lum(*b) - lum(*m), lum(*m)))
        .unzip();
    let n = d.len() as f64;
    let total: f64 = sm.iter().sum();
    let mean = d.iter().sum::<f64>() / n;
    let var = d.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
    (mean * n / total, var.sqrt() * n.sqrt() / total, d.len())
}

/// MDLC and EELC estimate the pixel value `manylight` estimates: over the translucent pixels of
/// a small sphere (2 samples per pixel), the relative difference of the summed luminance from
/// `manylight` at ε = 0.5 % is within 4 of its standard errors (the baselines' point sets are
/// independent per pixel) plus 0.5 % (manylight's own error, and MDLC's bias at ε = 1 %), with uniform points on
/// a material made wide enough for 2048 uniform points to find it (units_per_mm 0.5: red
/// diffuses 1.9 units over a unit sphere) and with importance-sampled points on the scene's own
/// skin. The standard errors are small enough for the test to see a 2 % bias.
#[test]
fn baselines_agree_with_manylight_within_statistical_error() {
    let settings = RenderSettings::default();
    let base = {
        let mut s = scene("sphere", 24, 18);
        s.camera.pixel_samples = 2;
        s
    };
    let mut wide = base.clone();
    for m in &mut wide.materials {
        if let sss_scene::MaterialKind::Translucent(t) = &mut m.kind {
            t.units_per_mm = 0.5;
        }
    }
    for (s, points, uniform) in [(&wide, 2048, true), (&base, 1024, false)] {
        let ml = integrators::build("manylight", &MethodOptions::new().with("rel-error", 0.005))
            .unwrap();
        let reference = render(s, ml.as_ref(), &settings, &NoProgress).unwrap();
        for (method, eps) in [("mdlc", 0.01), ("eelc", 0.02)] {
            let mut o = MethodOptions::new()
                .with("rel-error", eps)
                .with("irradiance-points", points);
            if uniform {
                o = o.with("uniform-points", "");
            }
            let m = integrators::build(method, &o).unwrap();
            let out = render(s, m.as_ref(), &settings, &NoProgress).unwrap();
            let (mean, se, n) = relative_difference(&out.subsurface, &reference.subsurface);
            eprintln!("{method} uniform={uniform}: {n} pixels, rel. diff {mean:.4} ± {se:.4}");
            assert!(n > 80, "{n} lit pixels");
            assert!(
                mean.abs() < 4.0 * se + 5e-3,
                "{method} uniform={uniform}: relative difference {mean} (se {se})"
            );
            assert!(
                se < 5e-3,
                "{method} uniform={uniform}: se {se} too large to see a bias"
            );
            let stat = |n: &str| out.stats.iter().find(|s| s.name == n).unwrap().value;
            assert_eq!(stat("irradiance_points"), points as f64);
            assert_eq!(stat("pixels_pair_cap"), 0.0);
            assert!(out.layer("pairs").unwrap().iter().any(|p| p[0] > 1.0));
        }
    }
}

/// Shadowed and black pixels terminate: on the slab (a wall's shadow over half of it, one
/// directional light), every pixel estimate ends without the pair cap, finite and ≥ 0; pixels
/// deep in the shadow are exactly 0 for MDLC (every pair refined to one point and the light) or
/// stop early for EELC. The pair cap holds. With the light's power set to 0 every pixel is
/// exactly 0 at once.
#[test]
fn baselines_terminate_on_shadowed_and_black_pixels() {
    let s = scene("slab", 32, 24);
    let mut black = s.clone();
    for l in &mut black.lights {
        if let Light::Directional { irradiance, .. } = l {
            *irradiance = [0.0; 3];
        }
    }
    let settings = RenderSettings::default();
    for method in ["mdlc", "eelc"] {
        for uniform in [false, true] {
            let mut o = MethodOptions::new().with("irradiance-points", 64);
            if uniform {
                o = o.with("uniform-points", "");
            }
            let m = integrators::build(method, &o).unwrap();
            let out = render(&s, m.as_ref(), &settings, &NoProgress).unwrap();
            let stat = |n: &str| out.stats.iter().find(|s| s.name == n).unwrap().value;
            assert!(stat("pixel_estimates") > 100.0);
            assert_eq!(stat("pixels_pair_cap"), 0.0, "{method}");
            assert!(
                out.subsurface
                    .iter()
                    .flatten()
                    .all(|v| v.is_finite() && *v >= 0.0)
            );
            let pairs = out.layer("pairs").unwrap();
            // At most 64 points × 1 light pairs in any pixel.
            assert!(pairs.iter().all(|p| p[0] <= 64.0), "{method}");
            assert!(
                out.subsurface.iter().any(|v| lum(*v) > 0.0),
                "{method}: the lit part is lit"
            );
            // The pair cap holds, is counted and warned about (ε = 0 never converges).
            let capped =
                integrators::build(method, &o.clone().with("rel-error", 0).with("max-pairs", 5))
                    .unwrap();
            let c = render(&s, capped.as_ref(), &settings, &NoProgress).unwrap();
            let cstat = |n: &str| c.stats.iter().find(|s| s.name == n).unwrap().value;
            assert!(c.layer("pairs").unwrap().iter().all(|p| p[0] <= 5.0));
            assert!(
                cstat("pixels_pair_cap") > 0.5 * cstat("pixel_estimates"),
                "{method}"
            );
            assert!(
                c.warnings.iter().any(|w| w.contains("pair cap")),
                "{:?}",
                c.warnings
            );
            let dark = render(&black, m.as_ref(), &settings, &NoProgress).unwrap();
            let stat = |n: &str| dark.stats.iter().find(|s| s.name == n).unwrap().value;
            assert_eq!(stat("vpls"), 0.0);
            assert!(dark.subsurface.iter().all(|v| *v == [0.0; 3]));
        }
    }
}

/// The same bits for 1 and 2 threads, with importance-sampled and uniform points.
#[test]
fn baselines_are_bit_identical_across_thread_counts() {
    let s = scene("sphere", 20, 15);
    for method in ["mdlc", "eelc"] {
        for uniform in [false, true] {
            let mut o = MethodOptions::new().with("irradiance-points", 128);
            if uniform {
                o = o.with("uniform-points", "");
            }
            let m = integrators::build(method, &o).unwrap();
            let run = |threads| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| render(&s, m.as_ref(), &RenderSettings::default(), &NoProgress))
                    .unwrap()
            };
            let (a, b) = (run(1), run(2));
            let bits =
                |v: &[[f64; 3]]| -> Vec<u64> { v.iter().flatten().map(|x| x.to_bits()).collect() };
            assert_eq!(
                bits(&a.subsurface),
                bits(&b.subsurface),
                "{method} uniform={uniform}"
            );
            assert_eq!(a.std_error, b.std_error);
            assert_eq!(a.layers, b.layers);
            assert!(a.subsurface.iter().any(|v| lum(*v) > 0.0));
        }
    }
}

#[test]
fn baselines_refuse_bad_options_unsupported_models_and_textures() {
    for method in ["mdlc", "eelc"] {
        for (k, v) in [
            ("rel-error", "-1"),
            ("irradiance-points", "0"),
            ("irradiance-points", "2000000"),
            ("irradiance-points", "many"),
            ("max-pairs", "0"),
            ("vpls", "0"),
        ] {
            let e = integrators::build(method, &MethodOptions::new().with(k, v))
                .err()
                .unwrap_or_else(|| panic!("{method} --{k} {v} accepted"))
                .to_string();
            assert!(e.contains(&format!("--{k}")), "{e}");
        }
        // Options of other methods are named as such.
        let e = integrators::build(method, &MethodOptions::new().with("selection", "bssrdf"))
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("--selection") && e.contains(method), "{e}");
        // The directional dipole: the same refusal as manylight, naming the material.
        let m =
            integrators::build(method, &MethodOptions::new().with("irradiance-points", 4)).unwrap();
        let e = render(
            &scene("picnic", 16, 12),
            m.as_ref(),
            &RenderSettings::default(),
            &NoProgress,
        )
        .unwrap_err();
        assert!(matches!(e, sss_render::Error::Unsupported(_)), "{e}");
        let e = e.to_string();
        assert!(e.contains("`apple`") && e.contains("directional"), "{e}");
        // A pre-scatter texture on a radial model.
        let mut toad = scene("toad", 16, 12);
        for mat in &mut toad.materials {
            if let sss_scene::MaterialKind::Translucent(t) = &mut mat.kind {
                t.model = sss_bssrdf::ModelKind::BetterDipole;
            }
        }
        let e = render(&toad, m.as_ref(), &RenderSettings::default(), &NoProgress)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("pre-scatter textures") && e.contains(method),
            "{e}"
        );
        // Memory: a million points per shading point do not fit 64 MiB; the error says which
        // method and which options to lower.
        let big = integrators::build(
            method,
            &MethodOptions::new().with("irradiance-points", 1 << 20),
        )
        .unwrap();
        let tight = RenderSettings {
            max_memory: 64 << 20,
            ..RenderSettings::default()
        };
        let e = render(&scene("sphere", 16, 12), big.as_ref(), &tight, &NoProgress)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains(method) && e.contains("--irradiance-points"),
            "{e}"
        );
    }
    // eelc's confidence level.
    let e = integrators::build("eelc", &MethodOptions::new().with("alpha", "1"))
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("--alpha"), "{e}");
}

/// The dark-pixel floor in the slab's shadow (a wall's shadow on a marble slab: the bounds
/// ignore visibility, so without a floor the shadowed clusters next to a dark pixel are split
/// long before the far lit ones that carry its value), against `exact` (point sums over the
/// renderer's irradiance samples: no VPLs, clusters, bounds or stopping rule). With F = 0.05
/// the pixels darker than F times the bright level stop as `Floor` at ΔI below ε · F · that
/// level, for fewer triplets than without it, and their error against `exact` stays within
/// that absolute target (plus 1 % of the value for `exact`'s own error) for at least 85 % of
/// them; pixels whose target the floor does not set are bit-identical with and without it.
#[test]
fn dark_pixels_stop_at_the_floor_and_keep_its_absolute_error() {
    let s = scene("slab", 24, 18);
    let settings = RenderSettings::default();
    let eps = 0.05;
    let floor = 0.05;
    let with = integrators::manylight::ManyLight {
        eps,
        dark_floor: floor,
        max_triplets: 20_000,
        ..Default::default()
    };
    let without = integrators::manylight::ManyLight {
        dark_floor: 0.0,
        ..with
    };
    let a = render(&s, &with, &settings, &NoProgress).unwrap();
    let b = render(&s, &without, &settings, &NoProgress).unwrap();
    let exact = render(
        &s,
        integrators::build("exact", &MethodOptions::new())
            .unwrap()
            .as_ref(),
        &settings,
        &NoProgress,
    )
    .unwrap();
    let stat =
        |o: &sss_render::RenderOutput, n: &str| o.stats.iter().find(|s| s.name == n).unwrap().value;
    let mut lit: Vec<f64> = exact
        .subsurface
        .iter()
        .map(|r| lum(*r))
        .filter(|v| *v > 0.0)
        .collect();
    lit.sort_by(f64::total_cmp);
    let level = lit[(0.9 * lit.len() as f64) as usize];
    let target_floor = eps * floor * level;
    eprintln!(
        "floor pixels {} (without {}), triplets {} vs {}, caps {} vs {}, level {level:.3e}",
        stat(&a, "pixels_floor"),
        stat(&b, "pixels_floor"),
        stat(&a, "triplets"),
        stat(&b, "triplets"),
        stat(&a, "pixels_triplet_cap"),
        stat(&b, "pixels_triplet_cap"),
    );
    let (mut same, mut dark, mut bad) = (0, 0, 0);
    for i in 0..exact.subsurface.len() {
        let r = lum(exact.subsurface[i]);
        let (va, vb) = (lum(a.subsurface[i]), lum(b.subsurface[i]));
        if vb > 10.0 * floor * level {
            same += 1;
            assert_eq!(a.subsurface[i], b.subsurface[i], "pixel {i}");
        } else if r > 0.0 {
            dark += 1;
            let err = (va - r).abs();
            let t = target_floor.max(eps * r) + 0.01 * r;
            bad += usize::from(err > t);
        }
    }
    eprintln!("{same} bright, {dark} dark, {bad} beyond their target");
    // The floor binds in the shadow and saves most of the work there; without it the deepest
    // pixels run to the cap.
    assert!(stat(&a, "pixels_floor") >= 20.0);
    assert_eq!(stat(&b, "pixels_floor"), 0.0);
    assert_eq!(stat(&a, "pixels_triplet_cap"), 0.0);
    assert!(stat(&b, "pixels_triplet_cap") >= 1.0);
    assert!(stat(&a, "triplets") * 5.0 < stat(&b, "triplets"));
    // The floored pixels' error holds: a 95 % interval, at least 85 % of 70-odd pixels.
    assert!(same >= 30 && dark >= 50, "{same} bright, {dark} dark");
    assert!(
        bad as f64 <= 0.15 * dark as f64,
        "{bad} of {dark} beyond their target"
    );
}

/// The bright level is the nearest-rank 90th percentile of the pilot's luminances, ignoring
/// non-finite ones; 0 without any.
#[test]
fn the_bright_level_is_the_ninetieth_percentile() {
    use sss_render::integrators::manylight::bright_level;
    let v: Vec<f64> = (1..=10).rev().map(f64::from).collect();
    assert_eq!(bright_level(v), 9.0);
    assert_eq!(bright_level((1..=20).map(f64::from).collect()), 18.0);
    assert_eq!(bright_level(vec![f64::NAN, 2.0, f64::INFINITY]), 2.0);
    assert_eq!(bright_level(vec![]), 0.0);
    assert_eq!(bright_level(vec![0.5]), 0.5);
}
