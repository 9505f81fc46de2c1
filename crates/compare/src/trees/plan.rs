//! What the trees experiment runs: the paper-scale bunny (`scenes/experiments/trees-bunny.toml`)
//! and the [`Plan`] of a full or `--quick` run.

use super::*;

/// The paper-scale bunny: the full-resolution scan (35 947 vertices, in metres) scaled ×64 to
/// the built-in bunny's size (about 10 units wide) on its ground, in skin1 with photon beam
/// diffusion, under the built-in bunny's point light and camera.
pub const BUNNY: &str = include_str!("../../../../scenes/experiments/trees-bunny.toml");

/// What one configuration runs.
pub(super) struct Plan {
    /// Resolutions (square) of the scaling runs.
    pub(super) resolutions: Vec<u32>,
    /// Resolution of the ε and ρ sweeps and the stage table.
    pub(super) sweep_resolution: u32,
    /// ε values of the sweep, cheapest first.
    pub(super) eps: Vec<f64>,
    /// ε values of `dual-tree-fmm`'s sweep, cheapest first.
    pub(super) fmm_eps: Vec<f64>,
    /// ρ values of the dual tree's ρ sweep (at [`FIXED_EPS`]; 0.75 is in the ε sweep).
    pub(super) rhos: Vec<f64>,
    /// ε values of the one-thread stage table.
    pub(super) table_eps: Vec<f64>,
}

/// ε of the scaling runs and the ρ sweep.
pub(super) const FIXED_EPS: f64 = 0.05;

/// ρ everywhere but the ρ sweep (the paper's value).
pub(super) const RHO: f64 = 0.75;

pub(super) fn plan(quick: bool) -> Plan {
    if quick {
        Plan {
            resolutions: vec![128, 256],
            sweep_resolution: 256,
            eps: vec![0.2, 0.05, 0.01],
            fmm_eps: vec![0.2, 0.05, 0.01],
            rhos: vec![0.25, 1.5],
            table_eps: vec![0.2, 0.05],
        }
    } else {
        Plan {
            resolutions: vec![256, 512, 1024, 2048],
            sweep_resolution: 1024,
            eps: vec![0.2, 0.1, 0.05, 0.01],
            fmm_eps: vec![0.2, 0.1, 0.05, 0.02, 0.01, 0.005],
            rhos: vec![0.25, 0.5, 1.5],
            table_eps: vec![0.2, 0.1, 0.05],
        }
    }
}

/// A run of the scaling series: the scaling runs, and the sweep's runs at [`FIXED_EPS`] and
/// ρ = [`RHO`] (the series' point at the sweep resolution).
pub(super) fn is_scaling(r: &TreeRun, p: &Plan) -> bool {
    r.experiment == "scaling"
        || (r.experiment == "eps"
            && r.resolution == p.sweep_resolution
            && r.eps == FIXED_EPS
            && r.rho.is_none_or(|x| x == RHO))
}
