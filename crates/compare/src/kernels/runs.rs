//! Timed kernel runs: each kernel method built for a material, filtered over the test image
//! and scored against the exact 2D convolution, and timed on the full frame with all threads
//! and with one; and the production skin kernel of Table 2, timed only.

use super::*;

/// One row of `kernels.csv`.
pub(super) struct Row {
    pub(super) material: String,
    pub(super) method: String,
    pub(super) placement: &'static str,
    pub(super) passes: usize,
    pub(super) taps_per_pixel: usize,
    pub(super) seconds_all: f64,
    pub(super) seconds_one: f64,
    pub(super) threads: usize,
    pub(super) rmse_exact2d: f64,
    pub(super) rel_rmse_exact2d: f64,
    pub(super) build_seconds: f64,
}

/// What one material's runs give: their rows, the red channel's singular values, and the
/// (seconds, relative error) points of its error-against-time curve.
pub(super) struct MaterialRuns {
    pub(super) rows: Vec<Row>,
    pub(super) spectrum: Vec<f64>,
    pub(super) points: Vec<(f64, f64)>,
}

/// Every kernel method for material `name` (its better-dipole `model`): built, filtered over
/// `test` against the exact 2D convolution with the full kernel on `spec`'s grid, and timed
/// on `big`. Writes the shadow-edge
/// pictures of the pre-integrated kernel with importance-sampled taps into `dir`.
pub(super) fn material_runs(
    name: &str,
    model: &dyn Bssrdf,
    spec: &Kernel2dSpec,
    test: &Frame,
    big: &Frame,
    all_threads: usize,
    dir: &Path,
) -> Result<MaterialRuns, Error> {
    let k2 = Kernel2d::from_model(model, spec).map_err(|e| Error(e.to_string()))?;
    let svd = svd::decompose(&k2).map_err(|e| Error(e.to_string()))?;
    let spectrum = svd.spectrum(0).to_vec();
    let opts = FilterOptions::default();
    let exact = convolve2d::exact(&test.input(), &k2, &opts).map_err(|e| Error(e.to_string()))?;
    let mut rows = Vec::new();
    let mut points = Vec::new();
    for method in KernelMethod::ALL {
        if method == KernelMethod::Exact2d {
            continue;
        }
        let placements: &[bool] = match method {
            KernelMethod::Svd1 | KernelMethod::Svd3 | KernelMethod::Svd6 => &[false],
            _ => &[true, false],
        };
        for &importance in placements {
            let settings = SeparableSettings {
                kernel: method,
                importance,
                ..SeparableSettings::default()
            };
            let t = Instant::now();
            let MaterialKernel::Separable(kernel) = build_kernel(model, &settings)
                .map_err(|e| Error(format!("{name} {method}: {e}")))?
            else {
                continue;
            };
            let build_seconds = t.elapsed().as_secs_f64();
            let out = screen_space::filter(&test.input(), &kernel, &opts)
                .map_err(|e| Error(e.to_string()))?;
            let (r, rel) = rmse(&out, &exact, &test.mask);
            let (seconds_all, seconds_one) = timed(big, &kernel, all_threads)?;
            if importance
                || matches!(
                    method,
                    KernelMethod::Svd1 | KernelMethod::Svd3 | KernelMethod::Svd6
                )
            {
                points.push((seconds_all, rel));
            }
            if method == KernelMethod::Preintegrated && importance {
                edge_pictures(name, test, &exact, &out, dir)?;
            }
            rows.push(Row {
                material: name.into(),
                method: method.name().into(),
                placement: if importance { "importance" } else { "uniform" },
                passes: kernel.passes(),
                taps_per_pixel: kernel.taps_per_pixel(),
                seconds_all,
                seconds_one,
                threads: all_threads,
                rmse_exact2d: r,
                rel_rmse_exact2d: rel,
                build_seconds,
            });
        }
    }
    Ok(MaterialRuns {
        rows,
        spectrum,
        points,
    })
}

/// The production skin kernel of Table 2 (its own separable product is its definition): cost
/// only, with the pass and tap counts engines would ship, importance-sampled and uniform taps.
pub(super) fn production_runs(big: &Frame, all_threads: usize) -> Result<Vec<Row>, Error> {
    let skin = make_model(
        ModelKind::BetterDipole,
        &Medium::preset("skin1").map_err(|e| Error(e.to_string()))?,
    );
    let total: Rgb = std::array::from_fn(|c| skin.total_diffuse_reflectance(c));
    let mut rows = Vec::new();
    for (importance, placement) in [
        (true, TapPlacement::Importance(7)),
        (false, TapPlacement::Uniform(7)),
    ] {
        let k = artist::kernel(&artist::PRODUCTION, total, placement)
            .map_err(|e| Error(e.to_string()))?;
        let (seconds_all, seconds_one) = timed(big, &k, all_threads)?;
        rows.push(Row {
            material: "production-skin".into(),
            method: "artist:production".into(),
            placement: if importance { "importance" } else { "uniform" },
            passes: k.passes(),
            taps_per_pixel: k.taps_per_pixel(),
            seconds_all,
            seconds_one,
            threads: all_threads,
            rmse_exact2d: f64::NAN,
            rel_rmse_exact2d: f64::NAN,
            build_seconds: 0.0,
        });
    }
    Ok(rows)
}

/// Seconds to filter `frame` with all threads and with one (the same run when there is one).
fn timed(frame: &Frame, kernel: &SeparableKernel, all_threads: usize) -> Result<(f64, f64), Error> {
    let seconds_all = timed_filter(frame, kernel, all_threads)?;
    let seconds_one = if all_threads > 1 {
        timed_filter(frame, kernel, 1)?
    } else {
        seconds_all
    };
    Ok((seconds_all, seconds_one))
}

/// RMSE of `a` against `b` over the masked pixels and channels, and that RMSE relative to
/// `b`'s mean.
fn rmse(a: &[[f32; 3]], b: &[[f32; 3]], mask: &[u32]) -> (f64, f64) {
    let (mut se, mut sum, mut n) = (0.0, 0.0, 0usize);
    for i in 0..a.len() {
        if mask[i] == NO_OBJECT {
            continue;
        }
        for c in 0..3 {
            let d = a[i][c] as f64 - b[i][c] as f64;
            se += d * d;
            sum += b[i][c] as f64;
            n += 1;
        }
    }
    let r = (se / n.max(1) as f64).sqrt();
    let mean = sum / n.max(1) as f64;
    (r, if mean > 0.0 { r / mean } else { 0.0 })
}

/// Seconds to filter `frame` on `threads` threads, best of two runs.
fn timed_filter(frame: &Frame, kernel: &SeparableKernel, threads: usize) -> Result<f64, Error> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error(e.to_string()))?;
    let opts = FilterOptions::default();
    let mut out = vec![[0.0f32; 3]; frame.width * frame.height];
    let mut scratch = screen_space::FilterScratch::default();
    let input = frame.input();
    let mut best = f64::INFINITY;
    // Best of two runs (the first warms the caches).
    for _ in 0..2 {
        let t = Instant::now();
        pool.install(|| screen_space::filter_into(&input, kernel, &opts, &mut scratch, &mut out))
            .map_err(|e| Error(e.to_string()))?;
        best = best.min(t.elapsed().as_secs_f64());
    }
    Ok(best)
}
