//! The experiment's outputs in words and tables: `kernels.csv` and the report section.

use super::*;

/// `kernels.csv`: one row per (material, kernel, tap placement), timed on a `fw`×`fh` frame.
pub(super) fn csv(rows: &[Row], (fw, fh): (usize, usize)) -> Csv {
    let mut csv = Csv::new([
        "material",
        "method",
        "placement",
        "passes",
        "taps_per_pixel",
        "threads",
        "seconds_frame",
        "seconds_frame_1thread",
        "rmse_exact2d",
        "rel_rmse_exact2d",
        "build_seconds",
        "frame",
    ]);
    for r in rows {
        csv.row([
            csv_text(&r.material),
            csv_text(&r.method),
            csv_text(r.placement),
            csv_text(r.passes),
            csv_text(r.taps_per_pixel),
            csv_text(r.threads),
            csv_num(Some(r.seconds_all)),
            csv_num(Some(r.seconds_one)),
            csv_num(Some(r.rmse_exact2d)),
            csv_num(Some(r.rel_rmse_exact2d)),
            csv_num(Some(r.build_seconds)),
            csv_text(format!("{fw}x{fh}")),
        ]);
    }
    csv
}

/// The report section: the kernels' table on the test image, and the world-space table
/// `world` ([`world_space`]).
pub(super) fn section(
    rows: &[Row],
    world: &[Vec<String>],
    (fw, fh): (usize, usize),
    cells: usize,
) -> Section {
    let table_rows: Vec<Vec<String>> = rows
        .iter()
        .map(|r| {
            vec![
                r.material.clone(),
                r.method.clone(),
                r.placement.to_string(),
                r.passes.to_string(),
                r.taps_per_pixel.to_string(),
                md_num(Some(r.seconds_all * 1e3), 3),
                md_num(Some(r.seconds_one * 1e3), 3),
                md_num(Some(100.0 * r.rel_rmse_exact2d), 3),
            ]
        })
        .collect();
    let body = format!(
        "Frame {fw}x{fh} at {MM_PER_PIXEL} mm per pixel; error on a {TEST_SIDE}² image with a \
         diagonal shadow edge and a bright spot against the exact 2D screen-space convolution \
         with the full {cells}² kernel (better dipole), jitter 0.1. Images in `kernels/`, spectra in \
         `singular_values.png`, error against time in `kernel_error_vs_time.png`, every number \
         in `kernels.csv`. Error against the world-space reference: the `separable` rows of \
         `results.csv`.\n\n{}",
        md_table(
            &[
                "material",
                "kernel",
                "taps",
                "1D passes",
                "taps/pixel",
                "ms/frame (all threads)",
                "ms/frame (1 thread)",
                "rel. RMSE vs exact 2D (%)"
            ],
            &table_rows
        )
    );
    let body = format!(
        "{body}\n\n#### Against the world-space `exact` reference\n\nThe full pipeline \
         (irradiance at the pixels, kernel, screen-space pass, F_t/(cπ)) on built-in scenes, \
         7 taps, 2 threads; error over translucent pixels. `exact2d` is the full 2D kernel in \
         screen space: what is left is the screen-space approximation itself.\n\n{}",
        md_table(
            &[
                "scene",
                "kernel",
                "taps",
                "seconds (total)",
                "RMSE",
                "rel. RMSE",
                "mean / ref. mean"
            ],
            world
        )
    );
    let best = rows
        .iter()
        .filter(|r| r.material == "skin1" && r.method == "preintegrated" && r.placement == "importance")
        .map(|r| format!("skin1 pre-integrated, 7 importance taps: {} ms per frame, {} % rel. RMSE vs exact 2D", md_num(Some(r.seconds_all * 1e3), 3), md_num(Some(100.0 * r.rel_rmse_exact2d), 3)))
        .next()
        .unwrap_or_default();
    Section {
        title: "Separable kernels (Jimenez et al. 2015)".into(),
        summary: format!(
            "{best}. See the table below for every material, kernel and tap placement.\n"
        ),
        body,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every column of `kernels.csv` is documented in `docs/compare.md`.
    #[test]
    fn every_csv_column_is_documented() {
        assert_eq!(
            crate::output::undocumented(&csv(&[], (1, 1))),
            Vec::<String>::new()
        );
    }
}
