//! The pictures and plots: s_p, the pixel clusters, relative differences, error against
//! time and scaling.

use super::*;

pub(super) fn pictures(ctx: &Context<'_>, runs: &[TreeRun], res: u32) -> Result<(), Error> {
    let dir = ctx.config.out.join("trees");
    std::fs::create_dir_all(&dir)
        .map_err(|e| Error(format!("cannot create {}: {e}", dir.display())))?;
    let e = |e: sss_render::Error| Error(e.to_string());
    let sweep: Vec<&TreeRun> = runs
        .iter()
        .filter(|r| r.experiment == "eps" && r.resolution == res)
        .collect();
    // The finest single-tree image stands in for the full reference of the difference images.
    let Some(finest) = sweep
        .iter()
        .filter(|r| r.method == "single-tree")
        .min_by(|a, b| a.eps.total_cmp(&b.eps))
    else {
        return Ok(());
    };
    let exposure = sss_render::image::exposure_or_auto(ctx.config.exposure, &finest.out.subsurface);
    let covered: Vec<bool> = finest.out.coverage.iter().map(|&c| c > 0.0).collect();
    let difference = |r: &TreeRun| -> Vec<Option<f64>> {
        r.out
            .subsurface
            .iter()
            .zip(&finest.out.subsurface)
            .zip(&covered)
            .map(|((a, b), &c)| {
                let m = (b[0] + b[1] + b[2]) / 3.0;
                (c && m > 0.0).then(|| ((a[0] + a[1] + a[2]) / 3.0 - m).abs() / m)
            })
            .collect()
    };
    if let Some((d, f)) = equal_time_pair(&sweep) {
        // Side by side, one colour scale (0 to 1 %), each against the finest single-tree
        // image: the paper's dual tree on the left, the local expansions given no more time
        // on the right, a 16-pixel gap between.
        let gap = 16usize;
        let n = res as usize;
        let (a, b) = (difference(d), difference(f));
        let mut values = Vec::with_capacity(n * (2 * n + gap));
        for y in 0..n {
            values.extend_from_slice(&a[y * n..(y + 1) * n]);
            values.extend(std::iter::repeat_n(None, gap));
            values.extend_from_slice(&b[y * n..(y + 1) * n]);
        }
        write_error_map(
            &dir.join("equal_time_difference.png"),
            2 * res + gap as u32,
            res,
            &values,
            0.01,
            &format!(
                "left: dual-tree eps={} rho={RHO}, {:.2} s | right: dual-tree-fmm eps={}, {:.2} s",
                d.eps,
                d.total(),
                f.eps,
                f.total(),
            ),
            "|a-b|/b",
        )
        .map_err(|e| Error(e.to_string()))?;
    }
    for r in &sweep {
        let name = format!("{}_eps{}", r.method, r.eps);
        sss_render::image::write_png(
            &dir.join(format!("{name}.png")),
            res,
            res,
            &r.out.subsurface,
            exposure,
        )
        .map_err(e)?;
        if std::ptr::eq(*r, *finest) {
            continue;
        }
        let values = difference(r);
        write_error_map(
            &dir.join(format!("{name}_difference.png")),
            res,
            res,
            &values,
            0.05,
            &format!(
                "{name}: relative difference from single-tree ε={}",
                finest.eps
            ),
            "|a-b|/b",
        )
        .map_err(|e| Error(e.to_string()))?;
    }
    if let Some(d) = sweep
        .iter()
        .find(|r| r.method == "dual-tree" && r.rho == Some(RHO))
    {
        for l in &d.out.layers {
            match l.name {
                "sampling_rate" => {
                    let values: Vec<Option<f64>> = l
                        .pixels
                        .iter()
                        .zip(&covered)
                        .map(|(p, &c)| c.then_some(p[0]))
                        .collect();
                    // Scaled to the 99th percentile: grazing pixels at the silhouettes reach
                    // s_p in the thousands (1/cos θ_o, clamped at 10⁻³) and would flatten the
                    // rest.
                    let mut sorted: Vec<f64> = values.iter().flatten().copied().collect();
                    sorted.sort_by(f64::total_cmp);
                    let p99 = sorted
                        .get((sorted.len() * 99 / 100).min(sorted.len().saturating_sub(1)))
                        .copied()
                        .unwrap_or(1.0);
                    write_error_map(
                        &dir.join("sampling_rate.png"),
                        res,
                        res,
                        &values,
                        p99.max(1e-12),
                        "s_p (samples per pixel, Eq. 5; scale to the 99th percentile)",
                        "s_p",
                    )
                    .map_err(|e| Error(e.to_string()))?;
                }
                "pixel_clusters" => {
                    sss_render::image::write_png(
                        &dir.join("pixel_clusters.png"),
                        res,
                        res,
                        &l.pixels,
                        1.0,
                    )
                    .map_err(e)?;
                }
                _ => {}
            }
        }
    }
    Ok(())
}

pub(super) fn plots(ctx: &Context<'_>, runs: &[TreeRun], p: &Plan) -> Result<(), Error> {
    let out = &ctx.config.out;
    let pe = |e: sss_plot::PlotError| Error(e.to_string());
    let curve = |exp: &str, method: &str| -> Vec<(f64, f64)> {
        runs.iter()
            .filter(|r| r.experiment == exp && r.method == method)
            .map(|r| (r.total(), r.score.rmse))
            .collect()
    };
    let series = vec![
        Series::line("single-tree (ε sweep)", curve("eps", "single-tree"))
            .with_style(SeriesStyle::LineMarkers)
            .with_color(PALETTE[1]),
        Series::line("dual-tree ρ=0.75 (ε sweep)", curve("eps", "dual-tree"))
            .with_style(SeriesStyle::LineMarkers)
            .with_color(PALETTE[2]),
        Series::line(
            format!("dual-tree ε={FIXED_EPS} (ρ sweep)"),
            curve("rho", "dual-tree"),
        )
        .with_style(SeriesStyle::LineMarkers)
        .with_color(PALETTE[3]),
        Series::line("dual-tree-fmm (ε sweep)", curve("eps", "dual-tree-fmm"))
            .with_style(SeriesStyle::LineMarkers)
            .with_color(PALETTE[4]),
    ];
    crate::output::plot_with_hover(
        &out.join("trees_error_vs_time.png"),
        &format!(
            "bunny {0}x{0}: RMSE against exact (subset) vs. total time",
            p.sweep_resolution
        ),
        ("seconds (total)", "RMSE"),
        &series,
        (true, true),
    )?;
    let scaling = |method: &str| -> Vec<(f64, f64)> {
        let mut v: Vec<(f64, f64)> = runs
            .iter()
            .filter(|r| is_scaling(r, p) && r.method == method)
            .map(|r| (f64::from(r.resolution).powi(2), r.stage("shading")))
            .collect();
        v.sort_by(|a, b| a.0.total_cmp(&b.0));
        v
    };
    line_plot(
        &out.join("trees_scaling.png"),
        &format!("bunny: final shading time vs. pixels (ε = {FIXED_EPS})"),
        "pixels",
        "shading seconds",
        &[
            Series::line("single-tree", scaling("single-tree"))
                .with_style(SeriesStyle::LineMarkers)
                .with_color(PALETTE[1]),
            Series::line("dual-tree", scaling("dual-tree"))
                .with_style(SeriesStyle::LineMarkers)
                .with_color(PALETTE[2]),
            Series::line("dual-tree-fmm", scaling("dual-tree-fmm"))
                .with_style(SeriesStyle::LineMarkers)
                .with_color(PALETTE[4]),
        ],
        true,
        true,
    )
    .map_err(pe)
}
