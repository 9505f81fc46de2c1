//! `volpath` against closed forms and conservation laws (its comparisons with Mitsuba 3 and
//! MCML are `volpath_mitsuba.rs` and `volpath_mcml.rs`): white furnaces, where a medium that
//! absorbs nothing sends back every photon that enters, and the lights a boundary can reach.

use crate::common::{scene_of, uv_sphere};
use glam::DVec3;
use sss_bssrdf::Rgb;
use sss_bssrdf::fresnel::ft_dielectric;
use sss_bssrdf::{Medium, ModelKind};
use sss_render::frame::Frame;
use sss_render::gbuffer::GSample;
use sss_render::integrators::{self, Integrator, MethodOptions};
use sss_render::progress::NoProgress;
use sss_render::scene::{Camera, Light, Material, MaterialKind, Scene, Translucent};

/// A grey or coloured medium that absorbs nothing (σ_a = 0), η = 1.3, 1 unit = 1 mm.
fn white(sigma_s: [f64; 3]) -> Material {
    Material {
        name: "white".into(),
        kind: MaterialKind::Translucent(Translucent {
            model: ModelKind::BetterDipole,
            medium: Medium::new([0.0; 3], sigma_s, 0.0, 1.3).unwrap(),
            units_per_mm: 1.0,
            texture: None,
            angular: Default::default(),
            sphere_radius: None,
            local_radius: false,
            drift: false,
            unscattered: false,
        }),
    }
}

/// Two spheres (radius 1 and 0.6, side by side, almost touching) under a uniform environment
/// of radiance 1, seen from the front at 48 × 32 pixels.
fn furnace(material: Material) -> Scene {
    let camera = Camera {
        position: DVec3::new(0.3, 0.4, 6.0),
        target: DVec3::new(0.3, 0.0, 0.0),
        up: DVec3::Y,
        vfov_deg: 30.0,
        width: 48,
        height: 32,
        pixel_samples: 1,
    };
    scene_of(
        vec![
            uv_sphere(DVec3::ZERO, 1.0, 48, 96),
            uv_sphere(DVec3::new(1.65, 0.0, 0.0), 0.6, 32, 64),
        ],
        material,
        vec![Light::Environment { radiance: [1.0; 3] }],
        camera,
    )
}

/// The camera samples of `frame` whose shading normal faces the camera, each with its value
/// and its Fresnel transmittance 1 − F(1.3, cos θ_o), what a white furnace returns there. (A
/// shading normal facing away, at the silhouette, makes the camera ray arrive from inside by
/// Mitsuba's convention, which we keep: those are left out.)
fn facing<'f>(
    frame: &'f Frame<'_>,
    values: &'f [Rgb],
) -> impl Iterator<Item = (&'f GSample, Rgb, f64)> + 'f {
    frame
        .gbuffer
        .samples
        .iter()
        .zip(values)
        .filter(|(g, _)| g.n.dot(g.wo) > 0.0)
        .map(|(g, v)| (g, *v, ft_dielectric(g.n.dot(g.wo), 1.3)))
}

fn volpath(options: MethodOptions) -> Box<dyn Integrator> {
    integrators::build("volpath", &options).unwrap()
}

/// A grey medium without absorption: every path leaves the objects (by way of the other
/// sphere too: paths re-enter) and sees the environment, so each camera sample's value is
/// exactly the Fresnel transmittance of its camera point, 1 − F(η, cos θ_o), whatever the
/// walk did; none is lost, none is capped.
#[test]
fn a_white_furnace_returns_every_photon_through_the_dielectric() {
    let scene = furnace(white([2.0; 3]));
    let frame = Frame::prepare(&scene, 1);
    let m = volpath(MethodOptions::new().with("spp", 8));
    let shaded = m.integrate(&frame, &NoProgress).unwrap();
    let mut checked = 0;
    for (g, v, want) in facing(&frame, &shaded.values) {
        for c in 0..3 {
            assert!(
                (v[c] - want).abs() < 1e-9,
                "{v:?} against {want} at {g:?}; {:?}",
                shaded.stats
            );
        }
        checked += 1;
    }
    assert!(checked > 100);
    let stat = |name: &str| shaded.stats.iter().find(|s| s.name == name).unwrap().value;
    assert_eq!(stat("lost_paths"), 0.0);
    assert_eq!(stat("capped_paths"), 0.0);
    // Paths went from one sphere into the other: more boundary events than a sphere alone
    // (enter and leave) gives.
    assert!(stat("interfaces_per_path") > 1.0);
    assert!(stat("collisions_per_path") > 1.0);
}

/// The same furnace in colour (σ_s 0.5, 2 and 8 per unit): distances are sampled in one
/// channel per path, so each channel's weight varies from path to path, but its mean must
/// still be 1 − F: the image's mean per channel within 4 standard errors of it.
#[test]
fn a_coloured_white_furnace_is_unbiased_in_every_channel() {
    let scene = furnace(white([0.5, 2.0, 8.0]));
    let frame = Frame::prepare(&scene, 3);
    let m = volpath(MethodOptions::new().with("spp", 64));
    let shaded = m.integrate(&frame, &NoProgress).unwrap();
    let gb = &frame.gbuffer;
    let se = shaded.std_error.as_ref().unwrap();
    let (mut got, mut want, mut var) = ([0.0; 3], 0.0, [0.0; 3]);
    for (g, v) in gb.samples.iter().zip(&shaded.values) {
        want += ft_dielectric(g.n.dot(g.wo), 1.3);
        for c in 0..3 {
            got[c] += v[c];
        }
    }
    for p in se {
        for c in 0..3 {
            var[c] += p[c] * p[c];
        }
    }
    for c in 0..3 {
        let sd = var[c].sqrt();
        assert!(sd > 0.0 && sd < 0.01 * want, "channel {c}: sd {sd}");
        assert!(
            (got[c] - want).abs() < 4.0 * sd,
            "channel {c}: {} against {want} ± {sd}",
            got[c]
        );
    }
}

/// Cycles' boundary: light enters and leaves diffusely with no reflection, so the white
/// furnace returns exactly the environment's radiance, 1, at every camera sample: the walk
/// always exits, and the exit's light, gathered over the cosine-weighted hemisphere, is π L.
/// (With two spheres a shadow ray may meet the other sphere; the single one is exact.)
#[test]
fn a_white_furnace_with_the_lambertian_boundary_returns_the_environment() {
    let mut scene = furnace(white([2.0; 3]));
    scene.objects.truncate(1);
    let frame = Frame::prepare(&scene, 1);
    let m = volpath(
        MethodOptions::new()
            .with("spp", 4)
            .with("boundary", "lambertian"),
    );
    let shaded = m.integrate(&frame, &NoProgress).unwrap();
    assert!(frame.gbuffer.samples.len() > 100);
    for v in &shaded.values {
        for c in 0..3 {
            assert!((v[c] - 1.0).abs() < 1e-9, "{v:?} {:?}", shaded.stats);
        }
    }
}

/// `--reentry no` ends a path where, having left a medium, it meets a translucent surface. On
/// one convex sphere no path can meet it again from outside, so the white furnace still
/// returns exactly 1 − F(η, cos θ_o) at every camera sample (no path ends on the surface it
/// just left). Beside a second sphere, every path still returns 1 − F or 0 (nothing is
/// absorbed), the image is darker, and each sphere loses about its view factor to the other:
/// by reciprocity A₁F₁₂ = A₂F₂₁, the small sphere (radius 0.6) about (1/0.6)² = 2.8 times the
/// big one's fraction (the spheres' exitance is near uniform and leaves both alike).
#[test]
fn without_reentry_a_convex_sphere_keeps_every_photon_and_two_lose_their_view_factors() {
    let no = || volpath(MethodOptions::new().with("spp", 16).with("reentry", "no"));
    let mut one = furnace(white([2.0; 3]));
    one.objects.truncate(1);
    let frame = Frame::prepare(&one, 1);
    let shaded = no().integrate(&frame, &NoProgress).unwrap();
    let mut checked = 0;
    for (g, v, want) in facing(&frame, &shaded.values) {
        assert!((v[0] - want).abs() < 1e-9, "{v:?} against {want} at {g:?}");
        checked += 1;
    }
    assert!(checked > 100);

    let two = furnace(white([2.0; 3]));
    let frame = Frame::prepare(&two, 1);
    let shaded = no().integrate(&frame, &NoProgress).unwrap();
    // Per sphere: Σ value and Σ (1 − F) over its camera samples facing the camera.
    let (mut got, mut full) = ([0.0; 2], [0.0; 2]);
    for (g, v, want) in facing(&frame, &shaded.values) {
        assert!(v[0] <= want + 1e-9, "{v:?} above {want}");
        got[g.object as usize] += v[0];
        full[g.object as usize] += want;
    }
    let lost = [1.0 - got[0] / full[0], 1.0 - got[1] / full[1]];
    eprintln!(
        "lost without reentry: big sphere {:.4}, small {:.4}",
        lost[0], lost[1]
    );
    assert!(lost[0] > 0.005 && lost[1] > 0.005, "{lost:?}");
    let ratio = lost[1] / lost[0];
    assert!(
        (ratio - (1.0f64 / 0.6).powi(2)).abs() < 0.3 * (1.0f64 / 0.6).powi(2),
        "small over big {ratio}"
    );
}

/// A point or directional light cannot be reached through a smooth dielectric: the render is
/// refused with an error naming the light and the Lambertian boundary, which renders it.
#[test]
fn delta_lights_are_refused_through_the_dielectric_and_lit_through_the_lambertian_boundary() {
    for light in [
        Light::Point {
            position: DVec3::new(0.0, 5.0, 5.0),
            intensity: [10.0; 3],
        },
        Light::Directional {
            direction: DVec3::new(0.0, -1.0, 0.0),
            irradiance: [1.0; 3],
        },
    ] {
        let mut scene = furnace(white([2.0; 3]));
        scene.lights.push(light.clone());
        let frame = Frame::prepare(&scene, 1);
        let e = volpath(MethodOptions::new().with("spp", 1))
            .integrate(&frame, &NoProgress)
            .unwrap_err();
        let msg = e.to_string();
        assert!(
            matches!(e, sss_render::Error::Unsupported(_))
                && msg.contains("light 1")
                && msg.contains("--boundary lambertian"),
            "{msg}"
        );
        // Lit by it alone through the Lambertian boundary: not black.
        scene.lights = vec![light];
        let frame = Frame::prepare(&scene, 1);
        let shaded = volpath(
            MethodOptions::new()
                .with("spp", 2)
                .with("boundary", "lambertian"),
        )
        .integrate(&frame, &NoProgress)
        .unwrap();
        assert!(shaded.values.iter().any(|v| v[0] > 0.0));
    }
}

#[test]
fn bad_options_are_one_line_errors() {
    for (k, v, words) in [
        ("spp", "0", "at least 1"),
        ("boundary", "glass", "dielectric, lambertian"),
        ("g", "1", "strictly between -1 and 1"),
        ("g", "forward", "neither `material` nor a number"),
        ("max-events", "0", "at least 1"),
        ("max-events", "-3", "neither `none` nor a whole number"),
        ("scattering", "double", "all, single, multiple"),
        ("reentry", "maybe", "yes, no"),
    ] {
        let e = integrators::build("volpath", &MethodOptions::new().with(k, v))
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains(words) && !e.contains('\n'), "{k}={v}: {e}");
    }
}

/// A cap on the events per path stops walks (a darker image) and says so in a warning.
#[test]
fn a_binding_event_cap_darkens_and_warns() {
    let scene = furnace(white([2.0; 3]));
    let frame = Frame::prepare(&scene, 1);
    let m = volpath(MethodOptions::new().with("spp", 4).with("max-events", 3));
    let shaded = m.integrate(&frame, &NoProgress).unwrap();
    let capped = shaded
        .stats
        .iter()
        .find(|s| s.name == "capped_paths")
        .unwrap()
        .value;
    assert!(capped > 0.0);
    assert!(
        frame
            .warnings()
            .iter()
            .any(|w| w.contains("--max-events 3"))
    );
    let dark = frame
        .gbuffer
        .samples
        .iter()
        .zip(&shaded.values)
        .filter(|(g, v)| v[0] < ft_dielectric(g.n.dot(g.wo), 1.3) - 1e-9)
        .count();
    assert!(dark > 0);
}

/// A half-space (the front face of a 400 mm block) of an index-matched medium (η = 1), albedo
/// 1/2, isotropic scattering, under a sun of 20° at normal incidence, seen at 45° at 32 × 32.
fn index_matched_half_space() -> Scene {
    let text = r#"
[camera]
position = [42.42640687119285, 0.0, 42.42640687119285]
target = [0.0, 0.0, 0.0]
fov = 10.0
resolution = [32, 32]

[[lights]]
type = "sun"
direction = [0.0, 0.0, -1.0]
irradiance = 1.0
angular_diameter = 20.0

[materials.m]
type = "translucent"
model = "standard-dipole"
sigma_a = 1.0
sigma_s = 1.0
eta = 1.0
units_per_mm = 1.0

[[objects]]
name = "block"
material = "m"
shape = "box"
size = [400.0, 400.0, 100.0]
transform = { translate = [0.0, 0.0, -50.0] }
"#;
    sss_render::scene::load_str(text, "half-space.toml", None, &Default::default()).unwrap()
}

/// `volpath --scattering ORDERS` on `scene`: the image mean over every pixel and its standard
/// error.
fn mean_of(scene: &Scene, scattering: &str, spp: u32, seed: u64) -> (f64, f64) {
    let m = volpath(
        MethodOptions::new()
            .with("spp", spp)
            .with("scattering", scattering),
    );
    let settings = sss_render::RenderSettings {
        seed,
        ..Default::default()
    };
    let out = sss_render::render(scene, m.as_ref(), &settings, &NoProgress).unwrap();
    let se = out.std_error.unwrap();
    let n = out.subsurface.len() as f64;
    let mean = out.subsurface.iter().map(|v| v[0]).sum::<f64>() / n;
    let var: f64 = se.iter().map(|s| s[0] * s[0]).sum();
    (mean, var.sqrt() / n)
}

/// Single scattering from an index-matched half-space has a closed form (Chandrasekhar 1960;
/// Hanrahan & Krueger 1993, Eq. 21 with isotropic phase): a beam of power E⊥ per unit area
/// across it, at μ₀ = cos θ_i, leaves L = α E⊥ μ₀ / (4π (μ₀ + μ)) at μ = cos θ_o. Summed over
/// the sun's disc (radiance E/(π sin²(δ/2))), `--scattering single` must give it; and the
/// image must be the sum of its single and multiple scattering (nothing reaches this camera
/// unscattered).
#[test]
fn single_scattering_matches_its_closed_form_and_the_orders_add_up() {
    let scene = index_matched_half_space();
    let (alpha, mu) = (0.5, std::f64::consts::FRAC_1_SQRT_2);
    let half = 10f64.to_radians();
    let l_sun = 1.0 / (std::f64::consts::PI * half.sin().powi(2));
    // ∫ over the disc of μ₀/(μ₀ + μ) dω: Simpson's rule in θ over [0, δ/2].
    let f = |t: f64| 2.0 * std::f64::consts::PI * t.sin() * t.cos() / (t.cos() + mu);
    let k = 200;
    let h = half / k as f64;
    let integral = h / 3.0
        * (0..=k)
            .map(|i| {
                let w = if i == 0 || i == k {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                w * f(i as f64 * h)
            })
            .sum::<f64>();
    let want = alpha / (4.0 * std::f64::consts::PI) * l_sun * integral;
    let (single, se) = mean_of(&scene, "single", 4096, 7);
    assert!(se < 0.012 * want, "too noisy to test: {se} of {want}");
    eprintln!("single scattering {single} ± {se}, closed form {want}");
    assert!(
        (single - want).abs() < 4.0 * se,
        "single scattering {single} ± {se}, closed form {want}"
    );
    let (all, se_a) = mean_of(&scene, "all", 256, 8);
    let (multiple, se_m) = mean_of(&scene, "multiple", 256, 9);
    let se_sum = (se_a * se_a + se_m * se_m + se * se).sqrt();
    assert!(multiple > 0.1 * all, "multiple {multiple} of {all}");
    assert!(
        (all - single - multiple).abs() < 4.0 * se_sum,
        "all {all} ≠ single {single} + multiple {multiple} (± {se_sum})"
    );
}
