//! The integrator contract (`sss_render::integrators`), checked for every registered method so
//! that a new method is held to it without a new test: one finite, non-negative value per
//! G-buffer sample, zero off visible translucent objects, bit-identical for any thread count
//! and run to run; plus the frame's shared pieces (irradiance samples built once, the radial
//! model request, the transmitted irradiance and exit weight).

use crate::common::cheap;
use glam::DVec3;
use sss_bssrdf::ModelKind;
use sss_bssrdf::fresnel::ft_dielectric;
use sss_bssrdf::fresnel_normalization;
use sss_render::frame::Frame;
use sss_render::integrators::{self, Integrator, METHODS, MethodOptions};
use sss_render::irradiance::IrradianceSettings;
use sss_render::lights::Incident;
use sss_render::progress::{NoProgress, Progress};
use sss_render::scene::{LoadOptions, MaterialKind, Scene, builtin};
use sss_render::shading::transmitted_irradiance;
use sss_render::{RenderSettings, render};
use std::f64::consts::PI;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};

/// A built-in scene at a quarter of its resolution in each direction (fast, still with
/// silhouettes, shadows and several objects).
fn small(name: &str, divide: u32) -> Scene {
    let mut s = builtin(name, &LoadOptions::default()).unwrap();
    s.camera.width = (s.camera.width / divide).max(1);
    s.camera.height = (s.camera.height / divide).max(1);
    s
}

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

/// Counts the progress the renderer reports.
#[derive(Default)]
struct Count {
    total: AtomicU64,
    done: AtomicU64,
}

impl Progress for Count {
    fn start(&self, total: u64) {
        self.total.store(total, Ordering::Relaxed);
    }
    fn advance(&self, n: u64) {
        self.done.fetch_add(n, Ordering::Relaxed);
    }
}

#[test]
fn every_method_keeps_the_contract_on_picnic() {
    // Picnic: five objects, five materials (four models, one opaque ground), point and
    // environment light.
    let picnic = small("picnic", 4);
    // Picnic with its directional-dipole material made radial, for the methods that sum
    // R_d·E·A over clusters and refuse the directional dipole.
    let mut radial = picnic.clone();
    let mut swapped = 0;
    for mat in &mut radial.materials {
        if let MaterialKind::Translucent(t) = &mut mat.kind
            && t.model == ModelKind::DirectionalDipole
        {
            t.model = ModelKind::BetterDipole;
            swapped += 1;
        }
    }
    assert_eq!(swapped, 1, "picnic has one directional-dipole material");
    let settings = RenderSettings::default();
    for m in METHODS {
        let method = integrators::build(m.name, &cheap(m.name)).unwrap();
        assert_eq!(method.name(), m.name);
        let mut scene = &picnic;
        let first = Frame::prepare(scene, settings.seed);
        if let Err(e) = pool(2).install(|| method.integrate(&first, &NoProgress)) {
            // The only acceptable refusal: the directional dipole, named.
            let msg = e.to_string();
            assert!(
                matches!(e, sss_render::Error::Unsupported(_))
                    && msg.contains("directional dipole")
                    && msg.contains("material `"),
                "{}: {msg}",
                m.name
            );
            scene = &radial;
        }
        let count = Count::default();
        let frame = Frame::prepare(scene, settings.seed);
        let shaded = pool(2).install(|| method.integrate(&frame, &count).unwrap());
        let n = frame.gbuffer.samples.len();
        assert_eq!(shaded.values.len(), n, "{}", m.name);
        assert_eq!(
            count.total.load(Ordering::Relaxed),
            0,
            "integrate does not restart"
        );
        assert_eq!(
            count.done.load(Ordering::Relaxed),
            n as u64,
            "{} progress",
            m.name
        );
        let mut lit = 0;
        for (g, v) in frame.gbuffer.samples.iter().zip(&shaded.values) {
            assert!(
                v.iter().all(|x| x.is_finite() && *x >= 0.0),
                "{}: {v:?}",
                m.name
            );
            if frame.shading_of(g.object).is_none() {
                assert_eq!(*v, [0.0; 3], "{}: value on an opaque sample", m.name);
            } else if v.iter().any(|x| *x > 0.0) {
                lit += 1;
            }
        }
        assert!(lit > 0, "{} shaded nothing", m.name);
        if let Some(se) = &shaded.std_error {
            assert_eq!(se.len(), frame.gbuffer.pixels());
            assert!(se.iter().flatten().all(|x| x.is_finite() && *x >= 0.0));
        }
        let names: Vec<&str> = shaded.layers.iter().map(|l| l.name).collect();
        assert_eq!(names, method.layer_names(), "{}", m.name);
        for l in &shaded.layers {
            assert_eq!(l.pixels.len(), frame.gbuffer.pixels());
        }
        let stages: Vec<&str> = frame.stages().iter().map(|s| s.name).collect();
        assert!(stages.contains(&"shading"), "{}: {stages:?}", m.name);
    }
}

#[test]
fn every_method_is_bit_identical_across_thread_counts_and_runs() {
    let scene = small("sphere", 4);
    let settings = RenderSettings::default();
    for m in METHODS {
        let method = integrators::build(m.name, &cheap(m.name)).unwrap();
        let run = |threads| {
            pool(threads).install(|| render(&scene, method.as_ref(), &settings, &NoProgress))
        };
        let a = run(1).unwrap();
        let b = run(2).unwrap();
        let c = run(2).unwrap();
        assert_eq!(a.method, m.name);
        for (x, y) in [(&a, &b), (&b, &c)] {
            assert_eq!(x.subsurface, y.subsurface, "{}", m.name);
            assert_eq!(x.total, y.total, "{}", m.name);
            assert_eq!(x.std_error, y.std_error, "{}", m.name);
        }
        // Another seed changes a stochastic method's image.
        if a.std_error.is_some() {
            let other = RenderSettings {
                seed: 7,
                ..settings.clone()
            };
            let d = render(&scene, method.as_ref(), &other, &NoProgress).unwrap();
            assert_ne!(a.subsurface, d.subsurface, "{}", m.name);
        }
        // Pixels without translucent coverage carry no subsurface light.
        for (i, cov) in a.coverage.iter().enumerate() {
            if *cov == 0.0 {
                assert_eq!(a.subsurface[i], [0.0; 3]);
            }
        }
    }
}

/// Only the point-based method asks for irradiance samples; the others leave them unbuilt.
#[test]
fn irradiance_samples_are_built_only_on_request_and_once() {
    let scene = small("sphere", 4);
    let frame = Frame::prepare(&scene, 1);
    assert_eq!(frame.samples_built(), (0, Vec::new()));
    let coarse = IrradianceSettings {
        spacing_mfp: 4.0,
        ..IrradianceSettings::default()
    };
    let a = frame.irradiance_samples(&coarse);
    let b = frame.irradiance_samples(&coarse);
    assert!(Arc::ptr_eq(&a, &b), "the same settings share one set");
    let built = |f: &Frame<'_>| f.stages().iter().filter(|s| s.name == "samples").count();
    assert_eq!(built(&frame), 1);
    let (count, spacing) = frame.samples_built();
    assert_eq!(count, a.iter().map(|s| s.samples.len()).sum::<usize>());
    assert_eq!(spacing.len(), frame.visible.len());
    let finer = IrradianceSettings {
        spacing_mfp: 2.0,
        ..coarse
    };
    let c = frame.irradiance_samples(&finer);
    assert_eq!(built(&frame), 2);
    let n = |s: &[sss_render::irradiance::ObjectSamples]| -> usize {
        s.iter().map(|o| o.samples.len()).sum()
    };
    assert!(
        n(&c) > 2 * n(&a),
        "halving the spacing about quadruples the count"
    );

    for m in METHODS {
        let method = integrators::build(m.name, &cheap(m.name)).unwrap();
        let out = render(
            &scene,
            method.as_ref(),
            &RenderSettings::default(),
            &NoProgress,
        )
        .unwrap();
        let stages: Vec<&str> = out.stages.iter().map(|s| s.name).collect();
        assert_eq!(
            out.irradiance_samples > 0,
            stages.contains(&"samples"),
            "{}",
            m.name
        );
        if method.irradiance_settings().is_none() {
            assert_eq!(
                out.irradiance_samples, 0,
                "{} built samples it does not use",
                m.name
            );
        }
    }
}

/// Methods that sum R_d·E·A ask for a radial model; the directional dipole answers with an
/// error naming the material and the model.
#[test]
fn radial_model_request_names_material_and_model() {
    let scene = small("toad", 8);
    let frame = Frame::prepare(&scene, 1);
    let mut directional = 0;
    for (m, sh) in frame.shading.iter().enumerate() {
        let Some(sh) = sh else { continue };
        let name = &scene.materials[m].name;
        assert_eq!(&sh.name, name);
        match sh.radial("dual-tree") {
            Ok(model) => {
                assert!(!sh.directional());
                assert!(model.rd_rgb(0.5).iter().all(|v| v.is_finite() && *v > 0.0));
            }
            Err(e) => {
                directional += 1;
                assert!(sh.directional());
                let msg = e.to_string();
                assert!(msg.contains(name.as_str()), "{msg}");
                assert!(msg.contains("directional-dipole"), "{msg}");
                assert!(msg.contains("dual-tree"), "{msg}");
            }
        }
    }
    assert_eq!(
        directional, 1,
        "toad's one material is the directional dipole"
    );
    // The sphere's skin is the better dipole: radial, so the request succeeds.
    let scene = small("sphere", 8);
    let frame = Frame::prepare(&scene, 1);
    let sh = frame.shading.iter().flatten().next().unwrap();
    assert!(!sh.directional());
    let model = sh.radial("dual-tree").unwrap();
    assert_eq!(model.rd_rgb(0.3), sh.bssrdf().rd_rgb(0.3));
}

/// Σ_k F_t(η, n·ω_k) E_k · texture, against the terms written out by hand.
#[test]
fn transmitted_irradiance_is_the_fresnel_weighted_textured_sum() {
    let n = DVec3::Z;
    let eta = 1.4;
    let dirs = [
        DVec3::Z,
        DVec3::new(0.6, 0.0, 0.8),
        DVec3::new(0.0, -0.8, 0.6),
    ];
    let mut packets: Vec<Incident> = dirs
        .iter()
        .enumerate()
        .map(|(k, &dir)| Incident {
            dir,
            e_cos: [1.0 + k as f64, 0.5, 0.25 * k as f64],
        })
        .collect();
    let tex = [0.5, 1.0, 2.0];
    let e = transmitted_irradiance(&mut packets, n, eta, tex);
    // Normal incidence: F_t = 1 − ((η − 1)/(η + 1))² exactly.
    let f0 = 1.0 - ((eta - 1.0) / (eta + 1.0)).powi(2);
    assert!((ft_dielectric(1.0, eta) - f0).abs() < 1e-12);
    let ft = [f0, ft_dielectric(0.8, eta), ft_dielectric(0.6, eta)];
    let expect_r = (ft[0] * 1.0 + ft[1] * 2.0 + ft[2] * 3.0) * 0.5;
    let expect_g = (ft[0] + ft[1] + ft[2]) * 0.5;
    let expect_b = (ft[1] * 0.25 + ft[2] * 0.5) * 2.0;
    for (got, want) in e.iter().zip([expect_r, expect_g, expect_b]) {
        assert!((got - want).abs() < 1e-14, "{got} vs {want}");
    }
    // The packets keep the texture (the directional dipole sums S over them).
    assert_eq!(packets[1].e_cos, [1.0, 0.5, 0.5]);
}

/// The exit weight is F_t(η, cos θ_o)/(cπ) with c = 1 − 2C₁(η).
#[test]
fn exit_weight_is_fresnel_over_c_pi() {
    let scene = small("sphere", 8);
    let frame = Frame::prepare(&scene, 1);
    let sh = frame.shading.iter().flatten().next().unwrap();
    let c = fresnel_normalization(sh.eta);
    for cos in [1.0f64, 0.5, 0.01] {
        let wo = DVec3::new((1.0f64 - cos * cos).sqrt(), 0.0, cos);
        let w = sh.exit_weight(DVec3::Z, wo);
        let want = ft_dielectric(cos, sh.eta) / (c * PI);
        assert!((w - want).abs() < 1e-15 * want.max(1e-300), "{w} vs {want}");
    }
    // η = 1.3 (skin1 in this scene): c lies near 0.87 (1 − 2C₁ with C₁ ≈ 0.065), and at
    // normal incidence F_t = 1 − (0.3/2.3)².
    assert!((sh.eta - 1.3).abs() < 1e-12);
    assert!((0.8..0.95).contains(&c), "c = {c}");
    let w0 = sh.exit_weight(DVec3::Z, DVec3::Z);
    assert!((w0 * c * PI - (1.0 - (0.3f64 / 2.3).powi(2))).abs() < 1e-12);
}

/// Unknown methods and options are refused with the names a user can fix.
#[test]
fn registry_errors_name_the_method_and_option() {
    let e = integrators::method("magic").unwrap_err().to_string();
    assert!(
        e.contains("magic") && e.contains("exact") && e.contains("pathtrace"),
        "{e}"
    );
    let e = integrators::build("pathtrace", &MethodOptions::new().with("taps", 3))
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("--taps") && e.contains("pathtrace") && e.contains("--spp"),
        "{e}"
    );
    let e = integrators::build("pathtrace", &MethodOptions::new().with("spp", 0))
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("--spp"), "{e}");
    let e = integrators::build("exact", &MethodOptions::new().with("spacing", "x"))
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("--spacing") && e.contains("`x`"), "{e}");
}

/// A method may be given as a plain value too: the registry's default matches the type's, for
/// every method.
#[test]
fn registry_defaults_match_the_settings_types() {
    use sss_render::integrators::exact::Exact;
    use sss_render::integrators::pathtrace::PathTrace;
    use sss_render::integrators::separable::Separable;
    let d = MethodOptions::new();
    assert_eq!(Exact::from_options(&d).unwrap(), Exact::default());
    assert_eq!(PathTrace::from_options(&d).unwrap(), PathTrace::default());
    assert_eq!(Separable::from_options(&d).unwrap(), Separable::default());
    use sss_render::integrators::{eelc::Eelc, mdlc::Mdlc};
    assert_eq!(Mdlc::from_options(&d).unwrap(), Mdlc::default());
    assert_eq!(Eelc::from_options(&d).unwrap(), Eelc::default());
    use sss_render::integrators::{dual_tree::DualTree, dual_tree_fmm::DualTreeFmm};
    use sss_render::integrators::{single_tree::SingleTree, volpath::VolPath};
    assert_eq!(SingleTree::from_options(&d).unwrap(), SingleTree::default());
    assert_eq!(DualTree::from_options(&d).unwrap(), DualTree::default());
    assert_eq!(
        DualTreeFmm::from_options(&d).unwrap(),
        DualTreeFmm::default()
    );
    assert_eq!(VolPath::from_options(&d).unwrap(), VolPath::default());
    use sss_render::integrators::{manylight::ManyLight, sparse_manylight::SparseManyLight};
    assert_eq!(ManyLight::from_options(&d).unwrap(), ManyLight::default());
    assert_eq!(
        SparseManyLight::from_options(&d).unwrap(),
        SparseManyLight::default()
    );
    let _: &dyn Integrator = &Exact::default();
}
