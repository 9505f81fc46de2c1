//! `cargo xtask compare --sparse`: `sparse-manylight` (the many-light estimator where the
//! screen-space sampling rate of Milaenen et al. 2019 asks, the other pixels reconstructed
//! with an interval) against `manylight` on whole frames, scored on a pixel subset against the
//! many-light comparison's path-traced reference ([`path_reference`]: no VPL clusters, bounds,
//! stopping rule or reconstruction, so it can show a reconstruction's error, which the
//! method's own checks cannot).
//!
//! **Frames.** The many-light comparison's seven scenes as they are ([`plan`]), and *windows
//! of 1080p frames* of the Buddha and the head ([`SparsePlan::windows`]): the centre of a
//! frame 1 080 pixels high seen through a camera whose field of view is narrowed to the
//! window, so that every pixel subtends what it does in the 1080p frame (a pinhole camera's
//! centred crop), with one camera sample per pixel. The sampling rate s_p is per pixel, so
//! the window's cells are the 1080p frame's cells there; the whole 1080p frame at ε = 2 %
//! would take hours with `manylight` on 2 cores.
//!
//! **What runs.** First, from the G-buffer alone, how many pixels each ρ of the sweep could
//! reconstruct ([`SparseManyLight::reconstructable_pixels`]). Where that is 0 at every ρ,
//! `sparse-manylight` estimates every pixel as `manylight` does, with the same image (a test
//! of the render crate shows it bit for bit), and nothing is rendered. Elsewhere: the
//! reference on a subset of [`Plan::subset`] translucent pixels drawn uniformly plus as many
//! drawn among the pixels the largest ρ could reconstruct (so that reconstructed pixels are
//! scored in numbers); `manylight` over the whole frame at the fixed ε; `sparse-manylight` at
//! each ε of the sweep at ρ = 1 and at the fixed ε at each larger ρ that reconstructs
//! something. Every run uses the reference's camera samples and VPLs and one estimator stream;
//! every time is the whole render's (set-up included).
//!
//! **Scores** (on the subset pixels whose reference resolves ε, [`Reference::resolves`]): the
//! fraction within ε of the reference (the estimation accuracy of the many-light comparison),
//! RMSE, the image mean over the reference's; on the reconstructed ones among them, the same
//! fraction and the coverage of their intervals (|Î − I| within the pixel's interval).
//!
//! Writes `sparse.csv` (one row per render), `sparse_cells.csv` (the reconstructable pixels
//! per frame and ρ) and `sparse/*.png` (each window's renders at the fixed ε and which pixels
//! were estimated).

use super::*;
use crate::output::md_pct;
use sss_bssrdf::Rgb;
use sss_render::RenderOutput;
use sss_render::integrators::sparse_manylight::SparseManyLight;

/// A window of a 1080p frame: the centre `size` of a frame [`WINDOW_ROWS`] high.
#[derive(Clone, Copy, Debug)]
pub(super) struct WindowSpec {
    /// Its name in the CSVs and the report.
    pub(super) name: &'static str,
    /// The scene file's text.
    pub(super) text: &'static str,
    /// Width and height in pixels.
    pub(super) size: (u32, u32),
}

/// The rows of the frames the windows are cut from (1080p).
pub(super) const WINDOW_ROWS: u32 = 1080;

/// What a run of the sparse comparison does.
#[derive(Clone, Debug)]
pub(super) struct SparsePlan {
    /// The many-light comparison's plan: its scenes, reference budget and subset size.
    pub(super) base: Plan,
    /// The windows of 1080p frames.
    pub(super) windows: Vec<WindowSpec>,
    /// ε of `sparse-manylight`'s sweep at ρ = 1.
    pub(super) eps: Vec<f64>,
    /// ε of `manylight`'s whole-frame render and of the ρ sweep.
    pub(super) fixed_eps: f64,
    /// ρ values, 1 first.
    pub(super) rhos: Vec<f64>,
}

pub(super) fn sparse_plan(quick: bool) -> SparsePlan {
    let base = plan(quick);
    if quick {
        SparsePlan {
            base,
            windows: vec![WindowSpec {
                name: "buddha-1080p",
                text: BUDDHA,
                size: (32, 32),
            }],
            eps: vec![0.05],
            fixed_eps: 0.05,
            rhos: vec![1.0, 4.0],
        }
    } else {
        SparsePlan {
            base,
            windows: vec![
                WindowSpec {
                    name: "buddha-1080p",
                    text: BUDDHA,
                    size: (128, 128),
                },
                WindowSpec {
                    name: "head-1080p",
                    text: HEAD,
                    size: (64, 64),
                },
            ],
            eps: vec![0.1, 0.05, 0.02],
            fixed_eps: 0.02,
            rhos: vec![1.0, 2.0, 4.0, 16.0],
        }
    }
}

/// `scene` seen through a `w` × `h` window at the centre of a frame `rows` pixels high: the
/// vertical field of view narrowed to tan(θ'/2) = tan(θ/2) · h / rows, so each pixel subtends
/// the angle it does in that frame (a pinhole camera's centred crop), one camera sample per
/// pixel.
pub(super) fn window(scene: &Scene, rows: u32, w: u32, h: u32) -> Scene {
    let mut s = scene.clone();
    let half = (0.5 * s.camera.vfov_deg).to_radians().tan() * f64::from(h) / f64::from(rows);
    s.camera.vfov_deg = 2.0 * half.atan().to_degrees();
    s.camera.width = w;
    s.camera.height = h;
    s.camera.pixel_samples = 1;
    s
}

/// One row of `sparse_cells.csv`.
#[derive(Clone, Debug)]
pub(super) struct CellRow {
    pub(super) scene: &'static str,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) pixel_samples: u32,
    pub(super) rho: f64,
    pub(super) translucent: usize,
    pub(super) reconstructable: usize,
}

/// One row of `sparse.csv`: a whole-frame render scored on the subset.
#[derive(Clone, Debug, Default)]
pub(super) struct SparseRow {
    pub(super) scene: &'static str,
    /// `manylight` or `sparse-manylight`.
    pub(super) method: &'static str,
    pub(super) eps: f64,
    /// ρ (`None` for manylight).
    pub(super) rho: Option<f64>,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) pixel_samples: u32,
    pub(super) seconds: f64,
    pub(super) translucent: usize,
    pub(super) reconstructed: usize,
    /// Triplets over the frame per translucent pixel.
    pub(super) triplets_per_pixel: f64,
    /// The many-light comparison's scores over the subset ([`Score`]).
    pub(super) scored: usize,
    pub(super) accuracy: f64,
    pub(super) rmse: f64,
    pub(super) bias: f64,
    pub(super) bias_se: f64,
    /// Scored subset pixels that were reconstructed, and the fraction of them within ε.
    pub(super) scored_reconstructed: usize,
    pub(super) accuracy_reconstructed: f64,
    /// The fraction of the scored reconstructed pixels within their interval.
    pub(super) coverage_reconstructed: f64,
}

/// The sparse experiment.
pub struct SparseExperiment;

impl Experiment for SparseExperiment {
    fn name(&self) -> &'static str {
        "sparse"
    }

    fn run(&self, ctx: &Context<'_>) -> Result<Section, Error> {
        let sp = sparse_plan(ctx.config.quick);
        let dir = ctx.config.out.join("sparse");
        std::fs::create_dir_all(&dir)
            .map_err(|e| Error(format!("cannot create {}: {e}", dir.display())))?;
        let mut cells = Vec::new();
        let mut rows = Vec::new();
        let mut skipped = Vec::new();
        let mut frames: Vec<(&'static str, Scene, bool)> = Vec::new();
        for spec in &sp.base.scenes {
            match load(ctx, spec, &sp.base)? {
                Some(s) => frames.push((spec.name, s, false)),
                None => skipped.push(spec.name.to_string()),
            }
        }
        for w in &sp.windows {
            let spec = super::plan::spec(w.name, w.text, Lighting::Quad, false);
            let unshrunk = Plan {
                shrink: 1,
                ..sp.base.clone()
            };
            match load(ctx, &spec, &unshrunk)? {
                Some(s) => frames.push((w.name, window(&s, WINDOW_ROWS, w.size.0, w.size.1), true)),
                None => skipped.push(w.name.to_string()),
            }
        }
        for (name, scene, is_window) in &frames {
            let pictures = is_window.then_some(dir.as_path());
            score_frame(ctx, &sp, name, scene, pictures, &mut cells, &mut rows)?;
        }
        cells_csv(&cells).write(&ctx.config.out.join("sparse_cells.csv"))?;
        sparse_csv(&rows).write(&ctx.config.out.join("sparse.csv"))?;
        Ok(sparse_report(&sp, &cells, &rows, &skipped))
    }
}

/// The settings of `sparse-manylight` at `eps` and `rho` on the comparison's VPLs and the
/// estimator stream `stream`.
fn sparse_at(ctx: &Context<'_>, eps: f64, rho: f64, stream: u64) -> SparseManyLight {
    SparseManyLight {
        estimator: ManyLight {
            stream,
            ..base(ctx, VPLS)
        },
        eps,
        rho,
        ..SparseManyLight::default()
    }
}

/// Eligibility over the ρ sweep, and where anything can be reconstructed the reference and
/// the renders of one frame; with `pictures`, the renders at the fixed ε written there as PNGs
/// (`manylight`'s exposure for all) with, for `sparse-manylight`, which pixels it estimated
/// (white) or reconstructed (grey).
fn score_frame(
    ctx: &Context<'_>,
    sp: &SparsePlan,
    name: &'static str,
    scene: &Scene,
    pictures: Option<&std::path::Path>,
    cells: &mut Vec<CellRow>,
    rows: &mut Vec<SparseRow>,
) -> Result<(), Error> {
    let seed = ctx.config.seed;
    let stream = seed + 1;
    let e = |e: sss_render::Error| Error(format!("scene {name}: {e}"));
    let frame = Frame::prepare(scene, seed);
    let translucent = translucent_pixels(&frame);
    let cam = &scene.camera;
    let mut can = Vec::new();
    // The pixels the last (largest) ρ could reconstruct, kept for the subset below.
    let mut widest = Vec::new();
    for &rho in &sp.rhos {
        widest = sparse_at(ctx, sp.fixed_eps, rho, stream)
            .reconstructable_pixels(&frame)
            .map_err(e)?;
        let n = widest.len();
        (ctx.log)(&format!(
            "sparse: {name} {}x{}: {n} of {} translucent pixels reconstructable at ρ = {rho}",
            cam.width,
            cam.height,
            translucent.len()
        ));
        cells.push(CellRow {
            scene: name,
            width: cam.width,
            height: cam.height,
            pixel_samples: cam.pixel_samples,
            rho,
            translucent: translucent.len(),
            reconstructable: n,
        });
        can.push((rho, n));
    }
    if can.iter().all(|&(_, n)| n == 0) {
        return Ok(());
    }
    // The subset: uniform over the translucent pixels, then as many among the pixels the
    // largest ρ could reconstruct.
    let p = &sp.base;
    let mut pixels = subset_pixels(&translucent, p.subset, seed ^ 0x4d4c);
    // `subset_pixels` returns its pixels sorted.
    let pool: Vec<usize> = widest
        .into_iter()
        .filter(|i| pixels.binary_search(i).is_err())
        .collect();
    pixels.extend(subset_pixels(&pool, p.subset, seed ^ 0x5350));
    (ctx.log)(&format!(
        "sparse: {name} path-traced reference of {} pixels",
        pixels.len()
    ));
    let r = path_reference(&frame, &pixels, p.reference, seed ^ 0x5245_4600, ctx.log);
    // Each render prepares its own frame (the same G-buffer and VPLs, from the same seed).
    drop(frame);
    let settings = RenderSettings {
        seed,
        ..RenderSettings::default()
    };
    let mut exposure = None;
    let mut run = |m: &dyn sss_render::integrators::Integrator,
                   method: &'static str,
                   eps: f64,
                   rho: Option<f64>|
     -> Result<(), Error> {
        (ctx.log)(&format!(
            "sparse: {name} {method} ε={eps}{}",
            rho.map(|r| format!(" ρ={r}")).unwrap_or_default()
        ));
        let t0 = Instant::now();
        let out = render(scene, m, &settings, &NoProgress).map_err(e)?;
        let seconds = t0.elapsed().as_secs_f64();
        if let (Some(dir), true) = (pictures, eps == sp.fixed_eps) {
            let x = *exposure.get_or_insert_with(|| {
                sss_render::image::exposure_or_auto(ctx.config.exposure, &out.total)
            });
            let tag = rho.map(|r| format!("_rho{r}")).unwrap_or_default();
            let png = |file: String, pixels: &[Rgb], x: f64| {
                let path = dir.join(file);
                sss_render::image::write_png(&path, cam.width, cam.height, pixels, x).map_err(e)
            };
            png(format!("{name}_{method}{tag}.png"), &out.total, x)?;
            if let Some(est) = out.layer("estimated") {
                let mask: Vec<Rgb> = est
                    .iter()
                    .zip(&out.coverage)
                    .map(|(v, &c)| match (c > 0.0, v[0] != 0.0) {
                        (false, _) => [0.0; 3],
                        (true, true) => [1.0; 3],
                        (true, false) => [0.2; 3],
                    })
                    .collect();
                png(format!("{name}_estimated{tag}.png"), &mask, 1.0)?;
            }
        }
        rows.push(score_render(
            &out,
            &r,
            SparseRow {
                scene: name,
                method,
                eps,
                rho,
                width: cam.width,
                height: cam.height,
                pixel_samples: cam.pixel_samples,
                seconds,
                translucent: translucent.len(),
                ..SparseRow::default()
            },
        ));
        Ok(())
    };
    let plain = ManyLight {
        eps: sp.fixed_eps,
        stream,
        ..base(ctx, VPLS)
    };
    run(&plain, OURS, sp.fixed_eps, None)?;
    if can.first().is_some_and(|&(_, n)| n > 0) {
        for &eps in &sp.eps {
            run(&sparse_at(ctx, eps, 1.0, stream), SPARSE, eps, Some(1.0))?;
        }
    }
    for &(rho, n) in can.iter().skip(1) {
        if n > 0 {
            let m = sparse_at(ctx, sp.fixed_eps, rho, stream);
            run(&m, SPARSE, sp.fixed_eps, Some(rho))?;
        }
    }
    Ok(())
}

/// The name of `sparse-manylight` in the CSV's `method` column.
pub(super) const SPARSE: &str = "sparse-manylight";

/// `row` completed with `out`'s scores on the reference's pixels.
pub(super) fn score_render(out: &RenderOutput, r: &Reference, mut row: SparseRow) -> SparseRow {
    let estimated = out.layer("estimated");
    let interval = out.layer("interval");
    let results: Vec<PixelResult> = r
        .pixels
        .iter()
        .map(|&i| PixelResult {
            subsurface: out.subsurface[i],
            ..PixelResult::default()
        })
        .collect();
    let s = score(&results, r, row.eps);
    let stat = |n: &str| out.stats.iter().find(|x| x.name == n).map(|x| x.value);
    row.reconstructed = stat("pixels_reconstructed").unwrap_or(0.0) as usize;
    row.triplets_per_pixel = stat("triplets").unwrap_or(0.0) / row.translucent.max(1) as f64;
    row.scored = s.scored;
    row.accuracy = s.accuracy;
    row.rmse = s.rmse;
    row.bias = s.bias;
    row.bias_se = s.bias_se;
    let (mut n, mut within, mut covered) = (0usize, 0usize, 0usize);
    if let (Some(est), Some(int)) = (estimated, interval) {
        for (k, &i) in r.pixels.iter().enumerate() {
            if est[i][0] != 0.0 || !r.resolves(k, row.eps) {
                continue;
            }
            let (a, b) = (lum(out.subsurface[i]), lum(r.values[k]));
            n += 1;
            within += usize::from((a - b).abs() < row.eps * b);
            covered += usize::from((a - b).abs() <= lum(int[i]));
        }
    }
    row.scored_reconstructed = n;
    let frac = |k: usize| if n > 0 { k as f64 / n as f64 } else { f64::NAN };
    row.accuracy_reconstructed = frac(within);
    row.coverage_reconstructed = frac(covered);
    row
}

pub(super) fn cells_csv(rows: &[CellRow]) -> Csv {
    let mut csv = Csv::new([
        "scene",
        "width",
        "height",
        "pixel_samples",
        "rho",
        "translucent",
        "reconstructable",
    ]);
    for r in rows {
        csv.row([
            csv_text(r.scene),
            csv_text(r.width),
            csv_text(r.height),
            csv_text(r.pixel_samples),
            csv_text(r.rho),
            csv_text(r.translucent),
            csv_text(r.reconstructable),
        ]);
    }
    csv
}

pub(super) fn sparse_csv(rows: &[SparseRow]) -> Csv {
    let mut csv = Csv::new([
        "scene",
        "method",
        "eps",
        "rho",
        "width",
        "height",
        "pixel_samples",
        "seconds",
        "translucent",
        "reconstructed",
        "triplets_per_pixel",
        "scored",
        "accuracy",
        "rmse",
        "bias",
        "bias_se",
        "scored_reconstructed",
        "accuracy_reconstructed",
        "coverage_reconstructed",
    ]);
    for r in rows {
        csv.row([
            csv_text(r.scene),
            csv_text(r.method),
            csv_text(r.eps),
            csv_num(r.rho),
            csv_text(r.width),
            csv_text(r.height),
            csv_text(r.pixel_samples),
            csv_num(Some(r.seconds)),
            csv_text(r.translucent),
            csv_text(r.reconstructed),
            csv_num(Some(r.triplets_per_pixel)),
            csv_text(r.scored),
            csv_num(Some(r.accuracy)),
            csv_num(Some(r.rmse)),
            csv_num(Some(r.bias)),
            csv_num(Some(r.bias_se)),
            csv_text(r.scored_reconstructed),
            csv_num(Some(r.accuracy_reconstructed)),
            csv_num(Some(r.coverage_reconstructed)),
        ]);
    }
    csv
}

/// `manylight`'s whole-frame render of `row`'s frame at `row`'s ε, if there is one.
fn plain_of<'a>(rows: &'a [SparseRow], row: &SparseRow) -> Option<&'a SparseRow> {
    rows.iter()
        .find(|x| x.scene == row.scene && x.method == OURS && x.eps == row.eps)
}

pub(super) fn sparse_report(
    sp: &SparsePlan,
    cells: &[CellRow],
    rows: &[SparseRow],
    skipped: &[String],
) -> Section {
    let mut body = String::new();
    let _ = writeln!(
        body,
        "`sparse-manylight` against `manylight` on whole frames, scored on a pixel subset \
         against the path-traced reference of the many-light comparison (half the subset drawn \
         among the pixels the largest ρ could reconstruct). The windows are the centres of \
         frames {WINDOW_ROWS} pixels high (the field of view narrowed to the window, one camera \
         sample per pixel): their pixels are 1080p pixels.\n"
    );
    if !skipped.is_empty() {
        let _ = writeln!(body, "Skipped (mesh not found): {}.\n", skipped.join(", "));
    }
    let _ = writeln!(
        body,
        "**Reconstructable pixels** (every eligible cell accepted; from the G-buffer and s_p \
         alone). Where the count is 0 at every ρ, `sparse-manylight` renders `manylight`'s \
         image and nothing was rendered.\n"
    );
    let mut names: Vec<&str> = Vec::new();
    for c in cells {
        if !names.contains(&c.scene) {
            names.push(c.scene);
        }
    }
    let mut header = vec!["frame".to_string(), "size".into(), "translucent".into()];
    header.extend(sp.rhos.iter().map(|r| format!("ρ = {r}")));
    let header_ref: Vec<&str> = header.iter().map(String::as_str).collect();
    let table: Vec<Vec<String>> = names
        .iter()
        .map(|n| {
            let of: Vec<&CellRow> = cells.iter().filter(|c| c.scene == *n).collect();
            let first = of[0];
            let mut row = vec![
                n.to_string(),
                format!(
                    "{}×{}, {} spp",
                    first.width, first.height, first.pixel_samples
                ),
                first.translucent.to_string(),
            ];
            row.extend(of.iter().map(|c| {
                format!(
                    "{} ({})",
                    c.reconstructable,
                    md_pct(Some(c.reconstructable as f64 / c.translucent.max(1) as f64))
                )
            }));
            row
        })
        .collect();
    body.push_str(&md_table(&header_ref, &table));
    let _ = writeln!(
        body,
        "\n**Renders** (`sparse.csv`): time and its ratio to `manylight`'s at the same ε (one \
         run each, same machine), pixels reconstructed, triplets per translucent pixel, the \
         fraction of scored pixels within ε of the reference (accuracy) and, of the \
         reconstructed ones, within ε and within their own interval (coverage), and the image \
         mean over the reference's (± its standard error).\n"
    );
    let table: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            let speed = plain_of(rows, r)
                .filter(|_| r.method == SPARSE)
                .map(|m| md_num(Some(m.seconds / r.seconds.max(1e-9)), 3) + "×")
                .unwrap_or_else(|| "–".into());
            vec![
                r.scene.to_string(),
                r.method.to_string(),
                md_pct(Some(r.eps)),
                r.rho.map(|x| x.to_string()).unwrap_or_else(|| "–".into()),
                md_num(Some(r.seconds), 3),
                speed,
                md_pct(Some(r.reconstructed as f64 / r.translucent.max(1) as f64)),
                md_num(Some(r.triplets_per_pixel), 4),
                format!("{} ({})", md_pct(Some(r.accuracy)), r.scored),
                if r.scored_reconstructed > 0 {
                    format!(
                        "{} / {} ({})",
                        md_pct(Some(r.accuracy_reconstructed)),
                        md_pct(Some(r.coverage_reconstructed)),
                        r.scored_reconstructed
                    )
                } else {
                    "–".into()
                },
                format!(
                    "{} ± {}",
                    md_num(Some(1.0 + r.bias), 4),
                    md_num(Some(r.bias_se), 2)
                ),
            ]
        })
        .collect();
    body.push_str(&md_table(
        &[
            "frame",
            "method",
            "ε",
            "ρ",
            "s",
            "speed-up",
            "reconstructed",
            "triplets / px",
            "accuracy (scored)",
            "reconstructed: within ε / interval (n)",
            "image mean / ref",
        ],
        &table,
    ));
    let _ = writeln!(
        body,
        "\nPictures, at ε = {}: `sparse/<window>_manylight.png`, \
         `_sparse-manylight_rho<ρ>.png` (one exposure) and `_estimated_rho<ρ>.png` (white: \
         estimated, grey: reconstructed).",
        md_pct(Some(sp.fixed_eps))
    );
    for w in &sp.windows {
        let rendered: Vec<&SparseRow> = rows
            .iter()
            .filter(|r| r.scene == w.name && r.eps == sp.fixed_eps)
            .collect();
        if rendered.is_empty() {
            continue;
        }
        let mut line = String::new();
        for r in &rendered {
            let tag = r.rho.map(|x| format!("_rho{x}")).unwrap_or_default();
            let label = r.rho.map(|x| format!(", ρ = {x}")).unwrap_or_default();
            let _ = write!(
                line,
                "![{}: {}{label}](sparse/{}_{}{tag}.png) ",
                w.name, r.method, w.name, r.method
            );
            if r.rho.is_some() {
                let _ = write!(
                    line,
                    "![{}: estimated (white){label}](sparse/{}_estimated{tag}.png) ",
                    w.name, w.name
                );
            }
        }
        let _ = writeln!(body, "\n{}", line.trim_end());
    }
    // The summary: per window, the best speed-up at the fixed ε and its accuracy.
    let mut summary = String::new();
    for w in &sp.windows {
        let best = rows
            .iter()
            .filter(|r| r.scene == w.name && r.method == SPARSE && r.eps == sp.fixed_eps)
            .filter_map(|r| plain_of(rows, r).map(|m| (m.seconds / r.seconds.max(1e-9), r, m)))
            .max_by(|a, b| a.0.total_cmp(&b.0));
        if let Some((s, r, m)) = best {
            let _ = writeln!(
                summary,
                "- {}: `sparse-manylight` at ε = {} and ρ = {} took {} of `manylight`'s time \
                 ({}× faster; {} of pixels reconstructed), accuracy {} against {}.",
                w.name,
                md_pct(Some(sp.fixed_eps)),
                r.rho.map(|x| x.to_string()).unwrap_or_default(),
                md_pct(Some(1.0 / s)),
                md_num(Some(s), 3),
                md_pct(Some(r.reconstructed as f64 / r.translucent.max(1) as f64)),
                md_pct(Some(r.accuracy)),
                md_pct(Some(m.accuracy)),
            );
        }
    }
    if summary.is_empty() {
        summary = "No window was rendered (meshes not found, or nothing reconstructable).\n".into();
    }
    Section {
        title: "Sparse many-light estimation against the path-traced reference".into(),
        summary,
        body,
    }
}
