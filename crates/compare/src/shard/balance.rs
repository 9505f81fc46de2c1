//! Dealing the work to the shards: each item's estimated cost and the deterministic
//! largest-first assignment every shard computes on its own.

use super::*;

/// Estimated seconds of the profile comparison (the references cached): about 2 s with
/// `--quick` on the 2-core machine, 10 s without.
pub(super) fn profiles_cost(quick: bool) -> f64 {
    if quick { 2.0 } else { 10.0 }
}

/// Estimated seconds of the kernel comparison: 45 s with `--quick` on the 2-core machine (a
/// 480×270 frame per kernel); the full run filters 1920×1080 frames.
pub(super) fn kernels_cost(quick: bool) -> f64 {
    if quick { 45.0 } else { 180.0 }
}

/// Seconds of one all-threads run at the middle of a method's `--quick` sweep on a scene of
/// 4 800 pixels, measured on the 2-core machine (`results.csv` of `compare --quick`, mean over
/// the built-in scenes); 1 for a method not listed.
pub(super) fn method_seconds(name: &str) -> f64 {
    match name {
        "exact" => 2.0,
        "pathtrace" => 0.04,
        "separable" => 0.015,
        "single-tree" => 0.5,
        "dual-tree" => 0.7,
        "dual-tree-fmm" => 0.3,
        "manylight" => 1.2,
        "mdlc" => 0.5,
        "eelc" => 1.4,
        _ => 1.0,
    }
}

/// Estimated seconds of a sweep unit on a scene of `pixels` pixels: the method's
/// [`method_seconds`] in proportion to the pixels, doubled per step along the sweep from its
/// middle (the sweeps double their work per step), times 2.5 with a one-thread run.
pub(super) fn unit_cost(unit: &SweepUnit, pixels: usize, quick: bool) -> f64 {
    let m = &METHODS[unit.method];
    let mid = (m.sweep.values)(quick).len() / 2;
    let step = 2f64.powi(unit.value as i32 - mid as i32);
    let one = if unit.with_one_thread(quick) {
        2.5
    } else {
        1.0
    };
    method_seconds(m.name) * (pixels.max(1) as f64 / 4800.0) * step * one
}

/// One item of the default job's work.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Work {
    /// Every model's profile against the Monte Carlo references.
    Profiles,
    /// The separable-kernel comparison.
    Kernels,
    /// A unit of the scenes sweep (index into the plan's units).
    Sweep(usize),
}

/// The shard (0-based) of each item of `costs`: largest cost first, each to the least-loaded
/// shard, ties to the lower shard and, among equal costs, the earlier item first.
pub fn assign(costs: &[f64], shards: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..costs.len()).collect();
    order.sort_by(|&a, &b| costs[b].total_cmp(&costs[a]).then(a.cmp(&b)));
    let mut load = vec![0.0f64; shards.max(1)];
    let mut out = vec![0; costs.len()];
    for i in order {
        let (s, _) = load
            .iter()
            .enumerate()
            .fold(
                (0, f64::INFINITY),
                |best, (s, &l)| {
                    if l < best.1 { (s, l) } else { best }
                },
            );
        out[i] = s;
        load[s] += costs[i].max(0.0);
    }
    out
}

/// Every item of the default job with its estimated cost, in report order.
pub(super) fn work(plan: &scenes::ScenePlan, quick: bool) -> Vec<(Work, f64)> {
    let mut v = vec![(Work::Profiles, profiles_cost(quick))];
    for (i, u) in plan.units.iter().enumerate() {
        let cam = &plan.scenes[u.scene].0.camera;
        let pixels = cam.width as usize * cam.height as usize;
        v.push((Work::Sweep(i), unit_cost(u, pixels, quick)));
    }
    v.push((Work::Kernels, kernels_cost(quick)));
    v
}
