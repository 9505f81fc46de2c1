//! `--truth --peers`: the same cases rendered by what users would run instead, on the same
//! error-against-time axes as our methods, each render scored against the case's `volpath`
//! reference like every other run: Mitsuba 3 (`volpathmis`, its defaults) and Blender Cycles
//! (the medium inside glass; its random-walk, random-walk (skin) and Christensen–Burley
//! subsurface at its own parameters), through `sss-peers`. A peer whose Python package is
//! missing is skipped with one sentence saying how to install it.

use super::*;
use sss_peers::{
    CyclesMode, CyclesRun, MitsubaRun, PeerRender, RR_DEFAULT, export, find_python,
    mitsuba_subsurface, render_cycles,
};

/// Which peers could run: (peer, its interpreter or why not), found once per run.
pub(crate) struct Peers {
    pub mitsuba: Result<PathBuf, String>,
    pub cycles: Result<PathBuf, String>,
}

impl Peers {
    /// Looks for the peers' packages.
    pub fn find() -> Peers {
        Peers {
            mitsuba: find_python(&["mitsuba", "numpy"]),
            cycles: find_python(&["bpy", "numpy"]),
        }
    }

    /// One line per peer for the report: what ran, or why not.
    pub fn notes(&self) -> Vec<String> {
        let line = |peer: &str, r: &Result<PathBuf, String>, ran: &str| match r {
            Ok(_) => format!("{peer}: {ran}"),
            Err(why) => format!("{peer}: skipped, {why}"),
        };
        vec![
            line(
                "Mitsuba 3",
                &self.mitsuba,
                "`volpathmis` with its defaults (Russian roulette from depth 5), rows \
                 `renderer = mitsuba`",
            ),
            line(
                "Blender Cycles",
                &self.cycles,
                "the medium inside glass (`method = volume`) and the Principled BSDF's \
                 subsurface at Cycles' own parameters inverted from the medium (`random-walk`, \
                 `random-walk-skin`, `burley`), rows `renderer = cycles`",
            ),
        ]
    }
}

/// The peers' runs of `case` (its `scene`) against `truth`, written under `dir`.
pub(crate) fn run_peers(
    ctx: &Context<'_>,
    peers: &Peers,
    case: &Case,
    scene: &Scene,
    plan: &Plan,
    truth: &Truth,
    dir: &Path,
) -> Result<Vec<TruthRun>, Error> {
    let mut runs = Vec::new();
    if peers.mitsuba.is_err() && peers.cycles.is_err() {
        return Ok(runs);
    }
    let json = export(scene, dir).map_err(|e| Error(e.to_string()))?;
    let threads = rayon::current_num_threads();
    let row = |renderer: &'static str, method: &'static str, spp: u32, r: &PeerRender| {
        if (r.width, r.height) != (truth.width, truth.height) {
            return Err(Error(format!(
                "truth {}: {renderer}'s image is {}×{}, the reference {}×{}",
                case.name(),
                r.width,
                r.height,
                truth.width,
                truth.height
            )));
        }
        (ctx.log)(&format!(
            "truth {}: {renderer} {method} at {spp} spp: {:.1} s",
            case.name(),
            r.seconds
        ));
        Ok(TruthRun {
            case: case.name(),
            scene: case.scene,
            medium: case.medium.name,
            light: case.lighting.name(),
            renderer,
            method,
            model: "",
            param: "spp",
            value: spp as f64,
            threads,
            seconds: r.seconds,
            shading: r.seconds,
            score: score(&r.mean(), truth),
            floor: None,
            warnings: 0,
        })
    };
    let fail = |e: sss_peers::Error| Error(format!("truth {}: {e}", case.name()));
    if let Ok(python) = &peers.mitsuba {
        for &spp in &plan.peer_spp {
            let run = MitsubaRun {
                spp,
                batches: 1,
                seed: ctx.config.seed,
                threads,
                rr_depth: RR_DEFAULT,
            };
            let r = mitsuba_subsurface(python, &json, &run).map_err(fail)?;
            runs.push(row("mitsuba", "volpathmis", spp, &r)?);
        }
    }
    if let Ok(python) = &peers.cycles {
        for mode in CyclesMode::ALL {
            for &spp in &plan.cycles_spp {
                let run = CyclesRun {
                    spp,
                    batches: 1,
                    seed: ctx.config.seed,
                    threads,
                    mode,
                };
                let name = format!("cycles_{}_{spp}", mode.name());
                let r = render_cycles(python, &json, &run, &name).map_err(fail)?;
                runs.push(row("cycles", mode.name(), spp, &r)?);
            }
        }
    }
    Ok(runs)
}
