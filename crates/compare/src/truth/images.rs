//! The pictures of a case: the reference, every model's `exact` image at the reference's
//! exposure, where each model errs (the signed difference from the reference, relative to the
//! reference's mean), and the error-against-time plot with `volpath`'s own curve.

use super::*;

/// The signed maps' range: ±50 % of the reference's mean luminance.
pub const SIGNED_RANGE: f64 = 0.5;

/// Writes `truth/<case>/reference.png`, `<model>.png` and `<model>_difference.png` for every
/// model image, at `exposure` (`None`: the reference's automatic one).
pub(crate) fn write_pictures(
    dir: &Path,
    case: &str,
    truth: &Truth,
    models: &[(&'static str, Vec<Rgb>)],
    exposure: Option<f64>,
) -> Result<(), Error> {
    std::fs::create_dir_all(dir)
        .map_err(|e| Error(format!("cannot create {}: {e}", dir.display())))?;
    let (w, h) = (truth.width, truth.height);
    let exposure = exposure.unwrap_or_else(|| auto_exposure(&truth.image));
    let png = |name: &str, px: &[Rgb]| {
        write_png(&dir.join(name), w, h, px, exposure).map_err(|e| Error(e.to_string()))
    };
    png("reference.png", &truth.image)?;
    let lum_mean = truth
        .pixels
        .iter()
        .map(|&i| luminance(truth.image[i]))
        .sum::<f64>()
        / truth.pixels.len().max(1) as f64;
    // The maps show the silhouette too, though it is not scored.
    let mut on = vec![false; truth.image.len()];
    for &i in &truth.translucent {
        on[i] = true;
    }
    for (model, image) in models {
        png(&format!("{model}.png"), image)?;
        let values: Vec<Option<f64>> = (0..image.len())
            .map(|i| {
                (on[i] && lum_mean > 0.0)
                    .then(|| (luminance(image[i]) - luminance(truth.image[i])) / lum_mean)
            })
            .collect();
        write_signed_map(
            &dir.join(format!("{model}_difference.png")),
            w,
            h,
            &values,
            SIGNED_RANGE,
            &format!("{case}: {model} (exact) − volpath"),
            "Δ luminance / mean",
        )
        .map_err(|e| Error(e.to_string()))?;
    }
    Ok(())
}

/// `truth_error_vs_time_<case>.png`: relative RMSE against total seconds, log-log: `volpath`'s
/// sweep, the fast methods' and the peers' as lines, each model under `exact` as one point.
pub(crate) fn write_plot(path: &Path, case: &str, runs: &[TruthRun]) -> Result<(), Error> {
    let mut series = Vec::new();
    // volpath solid black and Mitsuba dashed black; the fast methods (solid) and Cycles' modes
    // (dashed) in the palette's other seven colours; the models as points, in the palette's
    // colours again (told apart from the lines by their markers).
    let colour = |i: usize| PALETTE[1 + i % (PALETTE.len() - 1)];
    let points = |pred: &dyn Fn(&TruthRun) -> bool| -> Vec<(f64, f64)> {
        runs.iter()
            .filter(|r| pred(r) && r.score.rel_rmse > 0.0)
            .map(|r| (r.seconds, r.score.rel_rmse))
            .collect()
    };
    series.push(
        Series::line(
            "volpath",
            points(&|r| r.method == "volpath" && r.renderer == "sss"),
        )
        .with_style(SeriesStyle::LineMarkers)
        .with_color([0, 0, 0]),
    );
    let fast = FAST
        .iter()
        .map(|&name| (name, FAST_MODEL.name()))
        .chain(LOCAL_FAST.iter().map(|&name| (name, LOCAL_FAST_MODEL)))
        .chain(LOCAL_FAST.iter().map(|&name| (name, BOUNCE_FAST_MODEL)));
    for (i, (name, model)) in fast.enumerate() {
        let p = points(&|r| r.method == name && r.model == model);
        if !p.is_empty() {
            series.push(
                Series::line(format!("{name} ({model})"), p)
                    .with_style(SeriesStyle::LineMarkers)
                    .with_color(colour(i)),
            );
        }
    }
    let mitsuba = points(&|r| r.renderer == "mitsuba");
    if !mitsuba.is_empty() {
        series.push(
            Series::line("Mitsuba 3 volpathmis", mitsuba)
                .with_style(SeriesStyle::Dashed)
                .with_color([0, 0, 0]),
        );
    }
    for (i, mode) in sss_peers::CyclesMode::ALL.into_iter().enumerate() {
        let p = points(&|r| r.renderer == "cycles" && r.method == mode.name());
        if !p.is_empty() {
            series.push(
                Series::line(format!("Cycles {}", mode.name()), p)
                    .with_style(SeriesStyle::Dashed)
                    .with_color(colour(FAST.len() + 2 * LOCAL_FAST.len() + i)),
            );
        }
    }
    let names = ModelKind::ALL
        .iter()
        .map(|m| m.name())
        .chain(super::runs::VARIANTS);
    for (i, model) in names.enumerate() {
        let p = points(&|r| r.method == "exact" && r.model == model);
        if !p.is_empty() {
            series.push(
                Series::line(format!("exact, {model}"), p)
                    .with_style(SeriesStyle::Markers)
                    .with_color(colour(i)),
            );
        }
    }
    crate::output::plot_with_hover(
        path,
        &format!("{case}: error against volpath's reference vs. time"),
        ("seconds (total)", "relative RMSE"),
        &series,
        (true, true),
    )
}
