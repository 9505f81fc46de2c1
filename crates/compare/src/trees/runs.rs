//! One timed render of a tree method ([`TreeRun`]) and the stages it times.

use super::*;

/// One timed run.
pub(super) struct TreeRun {
    pub(super) experiment: &'static str,
    pub(super) resolution: u32,
    pub(super) method: &'static str,
    pub(super) eps: f64,
    pub(super) rho: Option<f64>,
    pub(super) threads: usize,
    pub(super) out: RenderOutput,
    pub(super) score: Score,
}

impl TreeRun {
    pub(super) fn total(&self) -> f64 {
        self.out.stages.iter().map(|s| s.seconds).sum()
    }
    /// Seconds of stage `name`, or "–" when the method has no such stage.
    pub(super) fn stage_cell(&self, name: &str) -> String {
        if self.out.stages.iter().any(|s| s.name == name) {
            md_num(Some(self.stage(name)), 3)
        } else {
            "–".into()
        }
    }
    pub(super) fn stage(&self, name: &str) -> f64 {
        self.out
            .stages
            .iter()
            .filter(|s| s.name == name)
            .map(|s| s.seconds)
            .sum()
    }
}

pub(super) fn run_on(
    scene: &Scene,
    method: &dyn Integrator,
    seed: u64,
    threads: usize,
) -> Result<RenderOutput, Error> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error(format!("cannot start {threads} threads: {e}")))?;
    let settings = RenderSettings {
        seed,
        ..RenderSettings::default()
    };
    pool.install(|| render(scene, method, &settings, &NoProgress))
        .map_err(|e| Error(format!("scene {}: {}: {e}", scene.name, method.name())))
}

pub(super) fn at_resolution(scene: &Scene, res: u32) -> Scene {
    let mut s = scene.clone();
    s.camera.width = res;
    s.camera.height = res;
    s
}

pub(super) const STAGES: [&str; 6] = [
    "samples",
    "illumination_tree",
    "fourier",
    "shading_tree",
    "shading",
    "gbuffer",
];
