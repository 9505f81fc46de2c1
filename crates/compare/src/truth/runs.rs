//! The runs of one case, each scored against its reference: every model under `exact`, the
//! fast methods over their sweeps (with `mc-table`, the model the scene files name, and those
//! that take it with each point's own ball, with and without one bounce of the light the
//! surfaces trade), and
//! `volpath` itself over its paths per pixel (with another seed than the reference's, so its
//! error is its own noise).

use super::*;

/// The fast methods scored against the truth, with the model of the scene files.
pub const FAST: [&str; 3] = ["dual-tree-fmm", "manylight", "separable"];

/// `exact`'s cap on irradiance samples per object here. `exact` costs pixels × samples: on
/// the true-size head the default cap (10⁵, samples 2.5 mean free paths apart) took 85 s a
/// model and still differed from this cap's image (4.5 apart, 32 s) by 25 % relative RMSE
/// (image means within 0.4 %), so there the models' floors come from `pathtrace`, which
/// discretises nothing; a capped run is marked in the `warnings` column.
pub const EXACT_SAMPLES: usize = 30_000;

/// `pathtrace`'s BSSRDF samples per pixel sample for the models' floors.
pub const PATHTRACE_SPP: u32 = 256;

/// The model the fast methods render with.
pub const FAST_MODEL: ModelKind = ModelKind::McTable;

/// The name of `mc-table` with `angular = "albedo"` in the runs' `model` column.
pub const ALBEDO_MODEL: &str = "mc-table+albedo";

/// The name of `mc-table` with `angular = "albedo"` and `sphere_radius = "auto"` (the profile
/// of a ball of the object's volume-to-area ratio) in the runs' `model` column.
pub const BALL_MODEL: &str = "mc-table+albedo+ball";

/// The name of [`BALL_MODEL`] with `drift = true` (obliquely entering light leaves ahead of its
/// entry point, as the random walk says) in the runs' `model` column.
pub const DRIFT_MODEL: &str = "mc-table+albedo+ball+drift";

/// The name of [`ALBEDO_MODEL`] with each point's own ball (`sphere_radius = "local"`), the
/// drift in each pair's ball (`drift = true`) and the light refracted through the object
/// without a collision (`unscattered = true`) in the runs' `model` column. Only `exact`
/// renders it.
pub const LOCAL_MODEL: &str = "mc-table+albedo+local+drift+unscattered";

/// The name of [`ALBEDO_MODEL`] with each point's own ball (`sphere_radius = "local"`) and no
/// drift in the runs' `model` column: the model [`LOCAL_FAST`] sweep too.
pub const LOCAL_FAST_MODEL: &str = "mc-table+albedo+local";

/// The fast methods that take each point's own ball, swept with [`LOCAL_FAST_MODEL`] besides
/// [`FAST_MODEL`], and with [`BOUNCE_FAST_MODEL`].
pub const LOCAL_FAST: [&str; 1] = ["dual-tree-fmm"];

/// The name of [`LOCAL_FAST_MODEL`] rendered with one bounce of the light the surfaces trade
/// (`--bounces 1`) and the light refracted through the object without a collision
/// (`unscattered = true`) in the runs' `model` column, swept by [`LOCAL_FAST`] too.
pub const BOUNCE_FAST_MODEL: &str = "mc-table+albedo+local+bounce+unscattered";

/// The `--bounces` of [`BOUNCE_FAST_MODEL`].
pub const FAST_BOUNCES: u32 = 1;

/// The models beyond [`ModelKind::ALL`] the experiment scores, in report order.
pub const VARIANTS: [&str; 4] = [ALBEDO_MODEL, BALL_MODEL, DRIFT_MODEL, LOCAL_MODEL];

/// One run scored against the truth.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct TruthRun {
    /// The case's name, scene, medium and light.
    pub case: String,
    pub scene: &'static str,
    pub medium: &'static str,
    pub light: &'static str,
    /// `sss` (the peers', `mitsuba` and `cycles`, come later).
    pub renderer: &'static str,
    /// The method (`exact`, `volpath`, ...).
    pub method: &'static str,
    /// The BSSRDF model (empty for `volpath`, which uses none).
    pub model: &'static str,
    /// The swept parameter and its value (empty and 0 for a single run).
    pub param: &'static str,
    pub value: f64,
    /// Threads it ran with.
    pub threads: usize,
    /// Total and shading seconds.
    pub seconds: f64,
    pub shading: f64,
    /// Its figures against the truth.
    pub score: Score,
    /// For a model rendered by `pathtrace`: its relative RMSE with its own noise removed too,
    /// the model's floor against the truth (None for other runs).
    pub floor: Option<f64>,
    /// Warnings the render gave (caps that bound).
    pub warnings: usize,
}

/// What a case's runs leave behind besides their rows: the image of every model under
/// `exact`, for the pictures.
pub(crate) struct CaseRuns {
    pub runs: Vec<TruthRun>,
    /// (model name, its `exact` image).
    pub model_images: Vec<(&'static str, Vec<Rgb>)>,
    /// Method–model pairs that cannot render the case, and why.
    pub unsupported: Vec<String>,
}

/// Runs everything of `case` against `truth`.
pub(crate) fn run_case(
    ctx: &Context<'_>,
    case: &Case,
    plan: &Plan,
    truth: &Truth,
) -> Result<CaseRuns, Error> {
    let cfg = ctx.config;
    let threads = rayon::current_num_threads();
    let mut out = CaseRuns {
        runs: Vec::new(),
        model_images: Vec::new(),
        unsupported: Vec::new(),
    };
    let scene_for = |model: ModelKind| {
        case.scene(model, plan.shrink, &cfg.mesh_dirs)
            .map_err(|e| Error(format!("truth {}: {e}", case.name())))
    };
    let row = |method: &'static str,
               model: &'static str,
               param: &'static str,
               value: f64,
               r: &RenderOutput| TruthRun {
        case: case.name(),
        scene: case.scene,
        medium: case.medium.name,
        light: case.lighting.name(),
        renderer: "sss",
        method,
        model,
        param,
        value,
        threads,
        seconds: r.seconds_total(),
        shading: r
            .stages
            .iter()
            .filter(|s| s.name == "shading")
            .map(|s| s.seconds)
            .sum(),
        score: score(&r.subsurface, truth),
        floor: None,
        warnings: r.warnings.len(),
    };
    let settings = |seed: u64| RenderSettings {
        seed,
        ..RenderSettings::default()
    };
    // Every model under `exact`, at the default comparison's reference spacing and at most
    // [`EXACT_SAMPLES`] irradiance samples per object.
    let exact = Exact {
        irradiance: IrradianceSettings {
            spacing_mfp: reference_spacing(cfg.quick),
            max_samples: EXACT_SAMPLES,
            ..IrradianceSettings::default()
        },
    };
    // Every model, and `mc-table` with the half-space's directional albedo for its angular
    // factors (`angular = "albedo"`, the model the measured deficit led to), then also with the
    // profile of the ball of the object's volume-to-area ratio (`sphere_radius = "auto"`), then
    // with the walk's drift too (`drift = true`): (name, scene).
    let variant = |k: usize| -> Result<(&'static str, Scene), Error> {
        match ModelKind::ALL.get(k) {
            Some(&model) => Ok((model.name(), scene_for(model)?)),
            None => {
                let mut scene = scene_for(ModelKind::McTable)?;
                with_albedo_weights(&mut scene);
                let name = VARIANTS[k - ModelKind::ALL.len()];
                if name == BALL_MODEL || name == DRIFT_MODEL {
                    with_ball_profile(&mut scene);
                }
                if name == LOCAL_MODEL {
                    with_local_balls(&mut scene);
                    with_unscattered(&mut scene);
                }
                if name == DRIFT_MODEL || name == LOCAL_MODEL {
                    with_drift(&mut scene);
                }
                Ok((name, scene))
            }
        }
    };
    let variants = ModelKind::ALL.len() + VARIANTS.len();
    for k in 0..variants {
        let (model, scene) = variant(k)?;
        let r = render(&scene, &exact, &settings(cfg.seed), &NoProgress)
            .map_err(|e| Error(format!("truth {}: exact with {model}: {e}", case.name())))?;
        (ctx.log)(&format!(
            "truth {}: exact with {model}: {:.1} s",
            case.name(),
            r.seconds_total()
        ));
        out.runs.push(row("exact", model, "", 0.0, &r));
        out.model_images.push((model, r.subsurface));
    }
    // Every model under `pathtrace` too: it converges to the integral `exact`'s sum
    // discretises, so where `exact`'s samples are coarse (the capped head) it is the model's
    // image; its own noise is removed from its floor.
    for k in 0..variants {
        let (model, scene) = variant(k)?;
        let method = PathTrace {
            spp: PATHTRACE_SPP,
            ..PathTrace::default()
        };
        let r = match render(&scene, &method, &settings(cfg.seed), &NoProgress) {
            Ok(r) => r,
            // Each point's own ball: `exact` only.
            Err(sss_render::Error::Unsupported(why)) => {
                out.unsupported.push(format!(
                    "`pathtrace` with {model} on `{}`: {why}",
                    case.name()
                ));
                continue;
            }
            Err(e) => {
                return Err(Error(format!(
                    "truth {}: pathtrace with {model}: {e}",
                    case.name()
                )));
            }
        };
        let se = r.std_error.clone().unwrap_or_default();
        let mut run = row("pathtrace", model, "spp", PATHTRACE_SPP as f64, &r);
        run.floor = Some(score_without_noise(&r.subsurface, &se, truth).rel_rmse);
        out.runs.push(run);
    }
    // The fast methods over their sweeps, with the scene files' model; those that take each
    // point's own ball, with it too.
    if plan.fast {
        let plain = scene_for(FAST_MODEL)?;
        let mut local = scene_for(FAST_MODEL)?;
        with_albedo_weights(&mut local);
        with_local_balls(&mut local);
        let mut full = local.clone();
        with_unscattered(&mut full);
        let jobs = FAST
            .iter()
            .map(|&name| (name, &plain, FAST_MODEL.name(), 0))
            .chain(
                LOCAL_FAST
                    .iter()
                    .map(|&name| (name, &local, LOCAL_FAST_MODEL, 0)),
            )
            .chain(
                LOCAL_FAST
                    .iter()
                    .map(|&name| (name, &full, BOUNCE_FAST_MODEL, FAST_BOUNCES)),
            );
        for (name, scene, model, bounces) in jobs {
            let m = integrators::method(name).map_err(|e| Error(e.to_string()))?;
            for v in (m.sweep.values)(cfg.quick) {
                let mut options = MethodOptions::new().with(m.sweep.option, v);
                if bounces > 0 {
                    options = options.with("bounces", bounces);
                }
                let method =
                    integrators::build(name, &options).map_err(|e| Error(e.to_string()))?;
                match render(scene, method.as_ref(), &settings(cfg.seed), &NoProgress) {
                    Ok(r) => out.runs.push(row(m.name, model, m.sweep.label, v, &r)),
                    Err(sss_render::Error::Unsupported(why)) => {
                        out.unsupported
                            .push(format!("`{name}` with {model} on `{}`: {why}", case.name()));
                        break;
                    }
                    Err(e) => {
                        return Err(Error(format!(
                            "truth {}: {name} with {model}: {e}",
                            case.name()
                        )));
                    }
                }
            }
        }
    }
    // `volpath` itself, with another seed than the reference's.
    let scene = scene_for(FAST_MODEL)?;
    for &spp in &plan.volpath_spp {
        let method = VolPath {
            spp,
            ..VolPath::default()
        };
        let r = render(&scene, &method, &settings(cfg.seed + 1), &NoProgress)
            .map_err(|e| Error(format!("truth {}: volpath: {e}", case.name())))?;
        out.runs.push(row("volpath", "", "spp", spp as f64, &r));
    }
    Ok(out)
}
