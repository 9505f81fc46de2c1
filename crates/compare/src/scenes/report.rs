//! The experiment's outputs from every unit's results: `results.csv`, the error-against-time
//! plots and the report section.

use super::*;

/// Writes `results.csv` and the error-against-time plots from the results of every unit of
/// `plan` (`results[i]` of `plan.units[i]`), and returns the report section. `info[s]` is scene
/// `s`'s info (`None` only for a scene without units). A method's units after its first
/// unsupported one on a scene are left out, as an unsharded run never runs them.
pub(crate) fn assemble(
    ctx: &Context<'_>,
    plan: &PlanOutline,
    info: &[Option<SceneInfo>],
    results: &[UnitResult],
) -> Result<Section, Error> {
    let cfg = ctx.config;
    // What each (scene, method) gave, in unit order, up to its first unsupported unit.
    let mut runs: Vec<Run> = Vec::new();
    // (scene, method) → the runs' start in `runs` of each of its units.
    let mut unit_runs: Vec<Vec<Vec<usize>>> =
        vec![vec![Vec::new(); METHODS.len()]; plan.scenes.len()];
    let mut unsupported: Vec<(usize, usize, String)> = Vec::new();
    for (unit, result) in plan.units.iter().zip(results) {
        if unsupported
            .iter()
            .any(|(s, m, _)| (*s, *m) == (unit.scene, unit.method))
        {
            continue;
        }
        match result {
            UnitResult::Runs(r) => {
                if !r.is_empty() {
                    unit_runs[unit.scene][unit.method].push(runs.len());
                }
                runs.extend(r.iter().cloned());
            }
            UnitResult::Unsupported(why) => {
                unsupported.push((unit.scene, unit.method, why.clone()));
            }
        }
    }
    let hosts: Vec<&Host> = runs.iter().fold(Vec::new(), |mut v, r| {
        if !v.contains(&&r.host) {
            v.push(&r.host);
        }
        v
    });
    let mixed = hosts.len() > 1;
    let mut body = String::new();
    let mut summary_rows = Vec::new();
    for (si, name) in plan.scenes.iter().enumerate() {
        let Some(info) = &info[si] else {
            continue;
        };
        // The first run of each unit is its all-threads run.
        let firsts =
            |mi: usize| -> Vec<&Run> { unit_runs[si][mi].iter().map(|&k| &runs[k]).collect() };
        let mut series = Vec::new();
        for (mi, m) in METHODS.iter().enumerate().filter(|(_, m)| swept(m)) {
            let points: Vec<(f64, f64)> = firsts(mi)
                .iter()
                .map(|r| (r.seconds_total(), r.rmse))
                .collect();
            series.push(
                Series::line(m.name, points)
                    .with_style(SeriesStyle::LineMarkers)
                    .with_color(PALETTE[(mi + 1) % 8]),
            );
        }
        let plot = cfg.out.join(format!("error_vs_time_{name}.png"));
        line_plot(
            &plot,
            &format!(
                "{name}: RMSE against exact vs. time ({} threads)",
                info.threads
            ),
            "seconds (total)",
            "RMSE",
            &series,
            true,
            true,
        )
        .map_err(|e| Error(e.to_string()))?;
        // Per-scene table.
        let _ = writeln!(
            body,
            "### {name}\n\n{}x{} pixels, {} translucent; reference `exact` with {} irradiance samples took {} s ({} threads). \
             Images in `scenes/{name}/`, curve in `error_vs_time_{name}.png`.\n",
            info.width,
            info.height,
            info.pixels,
            info.samples,
            md_num(Some(info.seconds), 3),
            info.threads,
        );
        let rows: Vec<Vec<String>> = runs
            .iter()
            .filter(|r| r.scene == *name)
            .map(|r| {
                let mut row = vec![
                    r.method.to_string(),
                    // A run whose caps bound (or whose units look wrong) is marked.
                    if r.warnings.is_empty() {
                        format!("{}={}", r.param, r.value)
                    } else {
                        format!("{}={} ⚠", r.param, r.value)
                    },
                    r.threads.to_string(),
                    md_num(Some(r.seconds_total()), 3),
                    md_num(r.stage("shading"), 3),
                    md_num(Some(r.rmse), 3),
                    md_pct(Some(r.rel_rmse)),
                    md_pct(Some(r.frac_within_eps)),
                    md_pct(r.within_3se),
                    md_num(Some(r.mean_ratio), 4),
                    md_num(Some(r.flip), 3),
                ];
                if mixed {
                    let h = hosts.iter().position(|h| **h == r.host).unwrap_or(0);
                    row.push(format!("H{}", h + 1));
                }
                row
            })
            .collect();
        let within = format!("within {} %", EPS * 100.0);
        let mut header = vec![
            "method",
            "param",
            "threads",
            "total s",
            "shading s",
            "RMSE",
            "rel. RMSE",
            &within,
            "within 3 SE",
            "mean / ref. mean",
            "FLIP",
        ];
        if mixed {
            header.push("host");
        }
        body.push_str(&md_table(&header, &rows));
        body.push('\n');
        let pt = METHODS.iter().position(|m| m.name == "pathtrace");
        let best_pt = pt.and_then(|mi| firsts(mi).last().copied());
        summary_rows.push(vec![
            name.clone(),
            info.pixels.to_string(),
            info.samples.to_string(),
            md_num(Some(info.seconds), 3),
            best_pt.map_or("–".into(), |r| {
                format!("{} spp: {} s", r.value, md_num(Some(r.seconds_total()), 3))
            }),
            best_pt.map_or("–".into(), |r| md_pct(Some(r.rel_rmse))),
            best_pt.map_or("–".into(), |r| md_num(Some(r.mean_ratio), 4)),
        ]);
    }
    results_csv(&runs).write(&cfg.out.join("results.csv"))?;
    let mut summary = md_table(
        &[
            "scene",
            "translucent pixels",
            "irradiance samples",
            "exact s",
            "pathtrace",
            "pathtrace rel. RMSE vs exact",
            "pathtrace mean / exact mean",
        ],
        &summary_rows,
    );
    for s in &plan.skipped {
        let _ = writeln!(summary, "\nSkipped {s}");
    }
    if !unsupported.is_empty() {
        let _ = writeln!(
            summary,
            "\nMethods that cannot render a scene (not run there):\n"
        );
        for (s, m, why) in &unsupported {
            let _ = writeln!(
                summary,
                "- `{}` on `{}`: {why}",
                METHODS[*m].name, plan.scenes[*s]
            );
        }
    }
    let mut warned: Vec<String> = Vec::new();
    for r in runs.iter().filter(|r| !r.warnings.is_empty()) {
        for w in &r.warnings {
            let line = format!("`{}` {} {}={}: {w}", r.scene, r.method, r.param, r.value);
            if !warned.contains(&line) {
                warned.push(line);
            }
        }
    }
    if !warned.is_empty() {
        let _ = writeln!(
            summary,
            "\nRuns marked ⚠ gave warnings (a cap bound, or implausible units; count in the \
             `warnings` column of `results.csv`):\n"
        );
        for w in &warned {
            let _ = writeln!(summary, "- {w}");
        }
    }
    if mixed {
        let _ = writeln!(
            summary,
            "\n**Times come from {} different hosts** (a merged sharded run); compare times only \
             between rows of the same host (column `host` of the tables, `host` and \
             `host_cores` in `results.csv`):\n",
            hosts.len()
        );
        for (i, h) in hosts.iter().enumerate() {
            let _ = writeln!(summary, "- H{}: {}", i + 1, h.label());
        }
    }
    let _ = writeln!(
        summary,
        "\nEvery run's figures (all threads, and one thread at the {} of each sweep) are in \
         `results.csv`; error is over \
         pixels covered by translucent objects, against the cached `exact` reference. The \
         path tracer converges to the surface integral that `exact` approximates with discrete \
         irradiance samples, so its mean ratio measures the point sum's discretisation plus \
         noise; per-pixel agreement within 3 standard errors is only meaningful at high spp \
         (with few samples, shadowed pixels often get all-zero estimates and a zero error bar).",
        if cfg.quick {
            "first (cheapest) point"
        } else {
            "middle"
        }
    );
    Ok(Section {
        title: "Scenes: references and error against run time".into(),
        summary,
        body,
    })
}
