//! The comparison's plots and pictures: error against time per scene, the baselines' sweeps,
//! and full-image renders with their error maps.

use super::*;

/// Full renders of the first scene at the picture ε with both selections: the image and the
/// triplets per pixel (Fig. 7).
pub(super) fn pictures(
    ctx: &Context<'_>,
    scene: &Scene,
    p: &Plan,
    dir: &std::path::Path,
) -> Result<(), Error> {
    let e = |e: sss_render::Error| Error(e.to_string());
    let settings = RenderSettings {
        seed: ctx.config.seed,
        ..RenderSettings::default()
    };
    let (w, h) = (scene.camera.width, scene.camera.height);
    let mut layers = Vec::new();
    for sel in [Selection::BssrdfAware, Selection::MaxExtent] {
        let m = ManyLight {
            eps: p.picture_eps,
            selection: sel,
            ..base(ctx, VPLS)
        };
        (ctx.log)(&format!(
            "manylight: {} picture, {} at ε={}",
            scene.name,
            selection_name(sel),
            p.picture_eps
        ));
        let out = render(scene, &m, &settings, &NoProgress).map_err(e)?;
        if sel == Selection::BssrdfAware {
            let path = dir.join(format!("{}.png", scene.name));
            let exposure = sss_render::image::exposure_or_auto(ctx.config.exposure, &out.total);
            sss_render::image::write_png(&path, w, h, &out.total, exposure).map_err(e)?;
        }
        let t = out
            .layers
            .iter()
            .find(|l| l.name == "triplets")
            .map(|l| l.pixels.iter().map(|v| v[0]).collect::<Vec<f64>>())
            .unwrap_or_default();
        let covered: Vec<bool> = out.coverage.iter().map(|&c| c > 0.0).collect();
        layers.push((sel, t, covered));
    }
    // One colour scale for both: the larger 99th percentile.
    let mut all: Vec<f64> = layers
        .iter()
        .flat_map(|(_, t, c)| t.iter().zip(c).filter(|(_, c)| **c).map(|(v, _)| *v))
        .collect();
    all.sort_by(f64::total_cmp);
    let max = all
        .get(((all.len() as f64) * 0.99) as usize)
        .copied()
        .unwrap_or(1.0)
        .max(1.0);
    for (sel, t, covered) in &layers {
        let values: Vec<Option<f64>> = t
            .iter()
            .zip(covered)
            .map(|(v, c)| if *c && *v > 0.0 { Some(*v) } else { None })
            .collect();
        let path = dir.join(format!(
            "{}_triplets_{}.png",
            scene.name,
            selection_name(*sel)
        ));
        write_error_map(
            &path,
            w,
            h,
            &values,
            max,
            &format!(
                "{}: triplets per pixel, {}",
                scene.name,
                selection_name(*sel)
            ),
            "triplets",
        )
        .map_err(|e| Error(format!("{}: {e}", path.display())))?;
    }
    Ok(())
}

/// Ours' sweep on `scene`: per ε of the plan (loosest first) the mean seconds and RMSE over
/// the streams, with that ε.
pub(super) fn ours_sweep(rows: &[Row], scene: &str, p: &Plan) -> Vec<(f64, f64, f64)> {
    p.eps
        .iter()
        .filter_map(|&eps| {
            let rs = accuracy_rows(rows, scene, OURS, eps);
            let n = rs.len() as f64;
            (!rs.is_empty()).then(|| {
                (
                    eps,
                    rs.iter().map(|x| x.seconds).sum::<f64>() / n,
                    rs.iter().map(|x| x.rmse).sum::<f64>() / n,
                )
            })
        })
        .collect()
}

/// A baseline's quality sweep on `scene`: (N, seconds, RMSE), fewest points first.
pub(super) fn baseline_sweep(rows: &[Row], scene: &str, method: &str) -> Vec<(u32, f64, f64)> {
    let mut v: Vec<(u32, f64, f64)> = rows
        .iter()
        .filter(|r| r.scene == scene && r.experiment == "quality" && r.method == method)
        .map(|r| (r.points, r.seconds, r.rmse))
        .collect();
    v.sort_by_key(|x| x.0);
    v
}

/// The baselines of Table 1, in its column order.
pub(super) const BASELINES: [&str; 4] = ["eelc-is", "mdlc-is", "eelc-uniform", "mdlc-uniform"];

pub(super) fn plots(ctx: &Context<'_>, rows: &[Row], p: &Plan) -> Result<(), Error> {
    let out = &ctx.config.out;
    let scenes: Vec<&str> = p.scenes.iter().map(|s| s.name).collect();
    let mut acc = Vec::new();
    for (k, name) in scenes.iter().enumerate() {
        let color = PALETTE[k % PALETTE.len()];
        for (method, label, style) in [
            (OURS, "ours".to_string(), SeriesStyle::LineMarkers),
            (
                "eelc-is",
                format!("EELC N = {}", p.eelc_points),
                SeriesStyle::Dashed,
            ),
        ] {
            let pts: Vec<(f64, f64)> = p
                .eps
                .iter()
                .filter_map(|&eps| {
                    let rs = accuracy_rows(rows, name, method, eps);
                    (!rs.is_empty()).then(|| (100.0 * eps, 100.0 * pooled(&rs).0))
                })
                .collect();
            if !pts.is_empty() {
                acc.push(Series {
                    name: format!("{name}, {label}"),
                    points: pts,
                    color: Some(color),
                    style,
                    ..Series::default()
                });
            }
        }
    }
    if !acc.is_empty() {
        acc.push(Series {
            name: "α = 95 %".into(),
            points: vec![
                (100.0 * p.eps[p.eps.len() - 1], 95.0),
                (100.0 * p.eps[0], 95.0),
            ],
            color: Some([120, 120, 120]),
            style: SeriesStyle::Dashed,
            ..Series::default()
        });
        line_plot(
            &out.join("manylight_accuracy.png"),
            "Estimation accuracy against ε (fraction with relative error < ε)",
            "ε (%)",
            "accuracy (%)",
            &acc,
            true,
            false,
        )
        .map_err(|e| Error(format!("manylight_accuracy.png: {e}")))?;
    }
    // RMSE against time per scene (Fig. 6).
    for name in &scenes {
        let mut series = Vec::new();
        let ours: Vec<(f64, f64)> = ours_sweep(rows, name, p)
            .iter()
            .map(|&(_, t, e)| (t, e))
            .collect();
        if ours.is_empty() {
            continue;
        }
        series.push(Series {
            name: "ours (ε sweep)".into(),
            points: ours,
            color: Some(PALETTE[0]),
            style: SeriesStyle::LineMarkers,
            ..Series::default()
        });
        for (k, method) in BASELINES.iter().enumerate() {
            let pts: Vec<(f64, f64)> = baseline_sweep(rows, name, method)
                .iter()
                .map(|&(_, t, e)| (t, e))
                .collect();
            if !pts.is_empty() {
                series.push(Series {
                    name: format!("{method} (N sweep, ε = {} %)", 100.0 * p.fixed_eps),
                    points: pts,
                    color: Some(PALETTE[(k + 1) % PALETTE.len()]),
                    style: SeriesStyle::LineMarkers,
                    ..Series::default()
                });
            }
        }
        let eelc_eps: Vec<(f64, f64)> = p
            .eps
            .iter()
            .flat_map(|&eps| accuracy_rows(rows, name, "eelc-is", eps))
            .map(|r| (r.seconds, r.rmse))
            .collect();
        if !eelc_eps.is_empty() {
            series.push(Series {
                name: format!("eelc-is (ε sweep, N = {})", p.eelc_points),
                points: eelc_eps,
                color: Some(PALETTE[5 % PALETTE.len()]),
                style: SeriesStyle::Markers,
                ..Series::default()
            });
        }
        let file = format!("manylight_rmse_{name}.png");
        crate::output::plot_with_hover(
            &out.join(&file),
            &format!("{name}: RMSE against time on the subset (frame set-up included)"),
            ("seconds", "RMSE"),
            &series,
            (true, true),
        )?;
    }
    let vp: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.experiment == "vpls")
        .map(|r| (r.vpls as f64, r.seconds))
        .collect();
    if !vp.is_empty() {
        line_plot(
            &out.join("manylight_vpls.png"),
            "Subset time against VPL count",
            "VPLs",
            "seconds",
            &[Series {
                name: "manylight".into(),
                points: vp,
                color: None,
                style: SeriesStyle::LineMarkers,
                ..Series::default()
            }],
            true,
            true,
        )
        .map_err(|e| Error(format!("manylight_vpls.png: {e}")))?;
    }
    Ok(())
}
