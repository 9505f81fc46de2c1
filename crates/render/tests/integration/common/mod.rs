//! Helpers shared by the render crate's integration tests.

// Each test file uses some of these.
#![allow(dead_code)]

pub mod rasterizer;

use sss_render::frame::Frame;
use sss_render::integrators::{Integrator, MethodOptions, Shaded};
use sss_render::irradiance::IrradianceSettings;
use sss_render::progress::NoProgress;
use sss_render::scene::{LoadOptions, Scene, builtin};

/// Cheap options per registered method, for tests that run every method on a small frame and
/// check properties that do not depend on accuracy (finite values, exact zeros, coverage,
/// determinism): the point-based methods on coarse irradiance samples, 2 paths per pixel,
/// and 32 irradiance points per shading point for the MDLC / EELC baselines (their default,
/// 4096, takes about 12 s a render even on a 24×18 frame).
pub fn cheap(name: &str) -> MethodOptions {
    match name {
        "exact" | "single-tree" | "dual-tree" | "dual-tree-fmm" => {
            MethodOptions::new().with("spacing", 2.0)
        }
        "pathtrace" => MethodOptions::new().with("spp", 2),
        "mdlc" | "eelc" => MethodOptions::new().with("irradiance-points", 32),
        _ => MethodOptions::new(),
    }
}

/// Built-in scene `name` at `w` × `h` pixels.
pub fn scene(name: &str, w: u32, h: u32) -> Scene {
    let mut s = builtin(name, &LoadOptions::default()).unwrap();
    s.camera.width = w;
    s.camera.height = h;
    s
}

/// The default irradiance-sample settings at `spacing` mean free paths.
pub fn irradiance(spacing: f64) -> IrradianceSettings {
    IrradianceSettings {
        spacing_mfp: spacing,
        ..IrradianceSettings::default()
    }
}

/// `m` on `frame`, without progress.
pub fn run(frame: &Frame<'_>, m: &dyn Integrator) -> Shaded {
    m.integrate(frame, &NoProgress).unwrap()
}
