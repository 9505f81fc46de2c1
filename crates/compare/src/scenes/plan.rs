//! What the scenes experiment runs: its units (a method at one value of its sweep on one
//! scene), the plan of a run, and the facts of each scene the report needs.

use super::*;

/// One unit of the sweep: a method (index into `METHODS`) at one value of its sweep (index)
/// on one scene (index into the plan's scenes), with all threads, and with one thread too at
/// one point of the sweep ([`SweepUnit::with_one_thread`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct SweepUnit {
    pub scene: usize,
    pub method: usize,
    pub value: usize,
}

impl SweepUnit {
    /// Every unit of `scenes` scenes, in report order: scene, then method, then sweep value.
    /// Only the methods that converge to their material's model are swept (the experiment
    /// scores them against `exact` with that model); `volpath`, which converges to light
    /// transport itself, is scored by `--truth`.
    pub fn all(scenes: usize, quick: bool) -> Vec<SweepUnit> {
        let mut units = Vec::new();
        for scene in 0..scenes {
            for (method, m) in METHODS.iter().enumerate().filter(|(_, m)| swept(m)) {
                for value in 0..(m.sweep.values)(quick).len() {
                    units.push(SweepUnit {
                        scene,
                        method,
                        value,
                    });
                }
            }
        }
        units
    }

    /// Whether the unit has a one-thread run too: only one point per sweep, since the
    /// speed-up and the same-bits check need one point per method, and one-thread runs of
    /// every point would double the main job's time. The middle of the sweep in a full run
    /// (a representative speed-up); with `--quick`, its first and cheapest point (every sweep
    /// runs from coarse to fine): the same-bits check is as strict there, and the quick run's
    /// one-thread runs took 74 of its 132 seconds of renders at the middle (slab's `manylight`
    /// at ε = 0.05 alone 17 s), 34 at the first point.
    pub fn with_one_thread(&self, quick: bool) -> bool {
        if quick {
            self.value == 0
        } else {
            self.value == (METHODS[self.method].sweep.values)(quick).len() / 2
        }
    }
}

/// The sweep: the scenes loaded (in order, with their TOML text), the ones skipped (a missing
/// mesh), and every unit.
pub(crate) struct ScenePlan {
    pub scenes: Vec<(Scene, String)>,
    pub skipped: Vec<String>,
    pub units: Vec<SweepUnit>,
}

/// What the report needs of a plan, without the scenes themselves: what a shard records and a
/// merge reads back.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PlanOutline {
    /// Scene names, in order.
    pub scenes: Vec<String>,
    /// Skip messages of scenes that were not loaded.
    pub skipped: Vec<String>,
    /// Every unit.
    pub units: Vec<SweepUnit>,
}

impl ScenePlan {
    /// The plan without its scenes.
    pub fn outline(&self) -> PlanOutline {
        PlanOutline {
            scenes: self.scenes.iter().map(|(s, _)| s.name.clone()).collect(),
            skipped: self.skipped.clone(),
            units: self.units.clone(),
        }
    }
}

/// Whether the experiment sweeps method `m`: those bound to their material's model.
pub(crate) fn swept(m: &Method) -> bool {
    m.converges_to == Converges::Model
}

/// Loads the run's scenes and lists the units of the sweep.
pub(crate) fn plan(ctx: &Context<'_>) -> Result<ScenePlan, Error> {
    let (scenes, skipped) = load_scenes(ctx, &ctx.config.scenes)?;
    let units = SweepUnit::all(scenes.len(), ctx.config.quick);
    Ok(ScenePlan {
        scenes,
        skipped,
        units,
    })
}

/// What the report says of a scene: its size, the reference's pixels, samples and time.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct SceneInfo {
    pub width: u32,
    pub height: u32,
    /// Pixels covered by translucent objects (where errors are measured).
    pub pixels: usize,
    /// Irradiance samples of the reference.
    pub samples: usize,
    /// Seconds the reference took (when it was rendered, maybe in an earlier run).
    pub seconds: f64,
    /// Threads of the run that reports it.
    pub threads: usize,
}

impl SceneInfo {
    /// The info as one tab-separated line (see [`SceneInfo::from_record`]).
    pub fn record(&self) -> String {
        format!(
            "{}\t{}\t{}\t{}\t{:e}\t{}",
            self.width, self.height, self.pixels, self.samples, self.seconds, self.threads
        )
    }

    /// Parses a line of [`SceneInfo::record`].
    pub fn from_record(line: &str) -> Result<SceneInfo, String> {
        let f: Vec<&str> = line.split('\t').collect();
        if f.len() != 6 {
            return Err(format!("{} fields, 6 expected", f.len()));
        }
        let bad = |i: usize| format!("field {}: `{}` is not a number", i + 1, f[i]);
        Ok(SceneInfo {
            width: f[0].parse().map_err(|_| bad(0))?,
            height: f[1].parse().map_err(|_| bad(1))?,
            pixels: f[2].parse().map_err(|_| bad(2))?,
            samples: f[3].parse().map_err(|_| bad(3))?,
            seconds: f[4].parse().map_err(|_| bad(4))?,
            threads: f[5].parse().map_err(|_| bad(5))?,
        })
    }
}
