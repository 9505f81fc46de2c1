//! `volpath` against closed forms and conservation laws (its comparisons with Mitsuba 3 and
//! MCML are `volpath_mitsuba.rs` and `volpath_mcml.rs`): white furnaces, where a medium that
//! absorbs nothing sends back every photon that enters, and the lights a boundary can reach.

use crate::common::{scene_of, uv_sphere};
use glam::DVec3;
use sss_bssrdf::fresnel::ft_dielectric;
use sss_bssrdf::{Medium, ModelKind};
use sss_render::frame::Frame;
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
    for (g, v) in frame.gbuffer.samples.iter().zip(&shaded.values) {
        // A shading normal facing away from the camera (at the silhouette) makes the camera
        // ray arrive from inside by Mitsuba's convention, which we keep: skipped here.
        let cos = g.n.dot(g.wo);
        if cos <= 0.0 {
            continue;
        }
        let want = ft_dielectric(cos, 1.3);
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
