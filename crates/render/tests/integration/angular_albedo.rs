//! `angular = "albedo"` (the half-space's directional albedo from the random walk as a radial
//! model's entry and exit weights) against real transport: `volpath`, which shares no code
//! with the model (no profile, no weights: light followed through the dielectric and the
//! medium).

use sss_render::integrators::{self, Integrator, MethodOptions};
use sss_render::progress::NoProgress;
use sss_render::scene::{Angular, MaterialKind, Scene, load_str};
use sss_render::{RenderSettings, render};

/// The front face (z = 0) of a skin1 block 400 mm wide and 100 mm deep (a half-space for its
/// mean free paths of 0.7–1.3 mm) under a uniform environment, seen from 60 mm at `view`
/// degrees from its normal, 16 × 16 pixels; `mc-table` with the given angular factors.
fn half_space(view: f64, angular: &str) -> Scene {
    let (s, c) = view.to_radians().sin_cos();
    let text = format!(
        "[camera]\nposition = [{:?}, 0.0, {:?}]\ntarget = [0.0, 0.0, 0.0]\nfov = 20.0\n\
         resolution = [16, 16]\n\n[[lights]]\ntype = \"environment\"\nradiance = 1.0\n\n\
         [materials.skin]\ntype = \"translucent\"\nmodel = \"mc-table\"\npreset = \"skin1\"\n\
         units_per_mm = 1.0\nangular = \"{angular}\"\n\n\
         [[objects]]\nname = \"block\"\nmaterial = \"skin\"\nshape = \"box\"\n\
         size = [400.0, 400.0, 100.0]\ntransform = {{ translate = [0.0, 0.0, -50.0] }}\n",
        60.0 * s,
        60.0 * c
    );
    load_str(&text, "half-space.toml", None, &Default::default()).unwrap()
}

/// Image mean per channel and its standard error (every pixel sees the half-space).
fn mean(scene: &Scene, method: &str, spp: u32, seed: u64) -> ([f64; 3], [f64; 3]) {
    let m = integrators::build(method, &MethodOptions::new().with("spp", spp)).unwrap();
    let settings = RenderSettings {
        seed,
        ..Default::default()
    };
    let out = render(scene, m.as_ref(), &settings, &NoProgress).unwrap();
    let se = out.std_error.unwrap();
    let n = out.subsurface.len() as f64;
    let mut m = [0.0; 3];
    let mut v = [0.0; 3];
    for (x, s) in out.subsurface.iter().zip(&se) {
        for c in 0..3 {
            m[c] += x[c] / n;
            v[c] += s[c] * s[c] / (n * n);
        }
    }
    (m, v.map(f64::sqrt))
}

/// Under uniform light a half-space returns A(θ_o) towards every θ_o (reciprocity), which the
/// albedo weights reproduce by construction: at 0° and 60° the model's image is within 3 % of
/// real transport in every channel, where Fresnel's weights are 6–11 % dark at 60°.
#[test]
fn the_albedo_weights_match_real_transport_under_uniform_light() {
    for view in [0.0, 60.0] {
        let (truth, se_t) = mean(&half_space(view, "fresnel"), "volpath", 1024, 11);
        let (albedo, se_a) = mean(&half_space(view, "albedo"), "pathtrace", 512, 12);
        let (fresnel, se_f) = mean(&half_space(view, "fresnel"), "pathtrace", 512, 12);
        for c in 0..3 {
            let (ra, rf) = (albedo[c] / truth[c], fresnel[c] / truth[c]);
            eprintln!("view {view}, channel {c}: albedo {ra:.4}, Fresnel {rf:.4} of the truth");
            let rel = |s: f64, m: f64| s / m;
            assert!(
                rel(se_t[c], truth[c]) < 0.006 && rel(se_a[c], albedo[c]) < 0.006,
                "view {view}, channel {c}: too noisy to test ({:?} {:?})",
                se_t,
                se_a
            );
            assert!(
                (ra - 1.0).abs() < 0.03,
                "view {view}, channel {c}: albedo weights {ra:.4} of the truth"
            );
            if view > 0.0 {
                assert!(
                    rf < 0.95 && rel(se_f[c], fresnel[c]) < 0.006,
                    "view {view}, channel {c}: Fresnel's {rf:.4}"
                );
            }
        }
    }
}

/// The many-light methods bound and cluster with one Fresnel weight per point: they refuse
/// the albedo weights with a one-line error naming the material, as they refuse the
/// directional dipole.
#[test]
fn the_many_light_methods_refuse_the_albedo_weights() {
    let scene = half_space(0.0, "albedo");
    assert!(matches!(
        &scene.materials[0].kind,
        MaterialKind::Translucent(t) if t.angular == Angular::Albedo
    ));
    for method in ["manylight", "sparse-manylight", "mdlc", "eelc"] {
        let m: Box<dyn Integrator> = integrators::build(method, &MethodOptions::new()).unwrap();
        let e = render(&scene, m.as_ref(), &RenderSettings::default(), &NoProgress)
            .err()
            .unwrap_or_else(|| panic!("{method} rendered the albedo weights"))
            .to_string();
        assert!(
            e.contains("`skin`") && e.contains("albedo") && !e.contains('\n'),
            "{method}: {e}"
        );
    }
}
