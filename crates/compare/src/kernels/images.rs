//! The pictures and plots: the shadow-edge test (input, exact 2D, pre-integrated, their
//! error), the point-light response with and without rotation jitter, the singular values
//! and error against frame time.

use super::*;

/// The shadow-edge test of material `name` under `dir`: its input, the exact 2D convolution,
/// the pre-integrated kernel's filtering `out` of it, and their relative error (red).
pub(super) fn edge_pictures(
    name: &str,
    test: &Frame,
    exact: &[[f32; 3]],
    out: &[[f32; 3]],
    dir: &Path,
) -> Result<(), Error> {
    let e = |e: sss_render::Error| Error(e.to_string());
    let w = TEST_SIDE as u32;
    let exp = auto_exposure(&to_rgb(exact));
    write_png(
        &dir.join(format!("{name}_edge_input.png")),
        w,
        w,
        &to_rgb(&test.irradiance),
        0.9 / 20.0f64.min(1.0),
    )
    .map_err(e)?;
    write_png(
        &dir.join(format!("{name}_edge_exact2d.png")),
        w,
        w,
        &to_rgb(exact),
        exp,
    )
    .map_err(e)?;
    write_png(
        &dir.join(format!("{name}_edge_preintegrated.png")),
        w,
        w,
        &to_rgb(out),
        exp,
    )
    .map_err(e)?;
    let floor = to_rgb(exact).iter().map(|p| p[0]).sum::<f64>() / (w * w) as f64 * 0.01;
    let values: Vec<Option<f64>> = out
        .iter()
        .zip(exact)
        .map(|(a, b)| Some(((a[0] - b[0]).abs() as f64) / (b[0] as f64).max(floor)))
        .collect();
    write_error_map(
        &dir.join(format!("{name}_edge_error.png")),
        w,
        w,
        &values,
        0.2,
        &format!("{name}: pre-integrated (7 taps) vs exact 2D, red"),
        "|a-b|/b",
    )
    .map_err(|e| Error(e.to_string()))
}

/// The point-light response of material `name` (its better-dipole `model`) with the default
/// kernel, with and without rotation jitter, under `dir`, at one exposure.
pub(super) fn point_response(name: &str, model: &dyn Bssrdf, dir: &Path) -> Result<(), Error> {
    let p = Frame::point(TEST_SIDE);
    let k = match build_kernel(model, &SeparableSettings::default())
        .map_err(|e| Error(e.to_string()))?
    {
        MaterialKernel::Separable(k) => k,
        MaterialKernel::Full(_) => unreachable!("pre-integrated is separable"),
    };
    // One exposure for the pair (the first's), so that they compare side by side.
    let mut exposure = None;
    for (label, jitter) in [("no_jitter", 0.0f32), ("jitter", 1.0)] {
        let o = FilterOptions {
            jitter_radius: jitter,
            ..FilterOptions::default()
        };
        let out = screen_space::filter(&p.input(), &k, &o).map_err(|e| Error(e.to_string()))?;
        let img = to_rgb(&out);
        let e = *exposure.get_or_insert_with(|| auto_exposure(&img));
        write_png(
            &dir.join(format!("{name}_point_{label}.png")),
            TEST_SIDE as u32,
            TEST_SIDE as u32,
            &img,
            e,
        )
        .map_err(|e| Error(e.to_string()))?;
    }
    Ok(())
}

/// The `mi`-th material's first 16 singular values (red) relative to the first.
pub(super) fn spectrum_series(name: &str, spectrum: &[f64], mi: usize) -> Series {
    let first = spectrum.first().copied().unwrap_or(0.0).max(1e-300);
    Series::line(
        format!("{name} (red)"),
        spectrum
            .iter()
            .take(16)
            .enumerate()
            .map(|(i, v)| ((i + 1) as f64, v / first))
            .collect(),
    )
    .with_style(SeriesStyle::LineMarkers)
    .with_color(PALETTE[(mi + 1) % 8])
}

/// The `mi`-th material's (seconds, relative error) points.
pub(super) fn curve_series(name: &str, points: Vec<(f64, f64)>, mi: usize) -> Series {
    Series::line(name, points)
        .with_style(SeriesStyle::Markers)
        .with_color(PALETTE[(mi + 1) % 8])
}

/// `singular_values.png` and `kernel_error_vs_time.png` under `out`.
pub(super) fn plots(
    out: &Path,
    spectra: &[Series],
    curves: &[Series],
    (fw, fh): (usize, usize),
    all_threads: usize,
) -> Result<(), Error> {
    line_plot(
        &out.join("singular_values.png"),
        "Singular values of the discretised R_d (better dipole, red), relative to the first",
        "index",
        "s_i / s_1",
        spectra,
        false,
        true,
    )
    .map_err(|e| Error(e.to_string()))?;
    crate::output::plot_with_hover(
        &out.join("kernel_error_vs_time.png"),
        &format!(
            "Separable kernels: rel. RMSE vs exact 2D against {fw}x{fh} frame time ({all_threads} threads)"
        ),
        ("seconds per frame", "relative RMSE"),
        curves,
        (true, true),
    )
}
