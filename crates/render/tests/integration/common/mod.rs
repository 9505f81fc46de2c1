//! Helpers shared by the render crate's integration tests.

// Each test file uses some of these.
#![allow(dead_code)]

pub mod rasterizer;

use sss_render::integrators::MethodOptions;

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
