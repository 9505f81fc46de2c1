//! The separable-kernel experiment (Jimenez et al. 2015): for each material and each kernel
//! method, with importance-sampled and uniform taps, the number of 1D passes and taps per
//! pixel, the time to filter a 1920×1080 frame with all threads and with one, and the error
//! against the exact 2D screen-space convolution with the full kernel at the same footprint
//! (on a 256×256 test image holding a diagonal shadow edge and a small bright spot).
//!
//! Writes `kernels.csv`, `singular_values.png`, `kernel_error_vs_time.png`, and under
//! `kernels/` the shadow-edge test (input, exact 2D, pre-integrated, their error) and the
//! point-light response with and without rotation jitter. Against the world-space `exact`
//! reference: every kernel (7 taps, importance and uniform) on the `sphere` (skin1) and `slab`
//! (marble) scenes, reusing the scenes experiment's cached references; the tap-count sweep is
//! the `separable` method of the scenes experiment.

use super::output::{csv_num, md_num, md_table, write_atomic};
use super::{Context, Error, Experiment, Section};
use sss_bssrdf::{Medium, ModelKind, Rgb, make_model};
use sss_plot::write_error_map;
use sss_plot::{PALETTE, Series, SeriesStyle, line_plot};
use sss_render::image::{auto_exposure, write_png};
use sss_render::kernel_choice::{KernelMethod, MaterialKernel, SeparableSettings, build_kernel};
use sss_separable::{
    FilterOptions, Kernel2d, Kernel2dSpec, NO_OBJECT, ScreenInput, SeparableKernel, TapPlacement,
    artist, convolve2d, screen_space, svd,
};
use std::fmt::Write as _;
use std::time::Instant;

/// Millimetres per pixel of the test images: skin1's red kernel spans ~100 pixels.
const MM_PER_PIXEL: f32 = 0.1;

/// Side of the error test image.
const TEST_SIDE: usize = 256;

/// A test image: irradiance, mask, depth and footprint buffers.
struct Frame {
    width: usize,
    height: usize,
    irradiance: Vec<[f32; 3]>,
    depth: Vec<f32>,
    mask: Vec<u32>,
    mm: Vec<f32>,
}

impl Frame {
    /// A diagonal shadow edge (lit below the line y = 0.6 x + 0.2 h) plus a bright 3-pixel spot
    /// in the shadow, one object, constant depth.
    fn edge(width: usize, height: usize) -> Frame {
        let mut irradiance = vec![[0.0f32; 3]; width * height];
        let (sx, sy) = (width as f64 * 0.7, height as f64 * 0.25);
        for y in 0..height {
            for x in 0..width {
                let lit = (y as f64) > 0.6 * x as f64 + 0.2 * height as f64;
                let spot = ((x as f64 - sx).powi(2) + (y as f64 - sy).powi(2)) < 2.25;
                let v = if spot {
                    20.0
                } else if lit {
                    1.0
                } else {
                    0.0
                };
                irradiance[y * width + x] = [v; 3];
            }
        }
        Frame {
            width,
            height,
            irradiance,
            depth: vec![1000.0; width * height],
            mask: vec![0; width * height],
            mm: vec![MM_PER_PIXEL; width * height],
        }
    }

    /// One lit pixel in the middle (the point-light response).
    fn point(side: usize) -> Frame {
        let mut f = Frame::edge(side, side);
        f.irradiance = vec![[0.0; 3]; side * side];
        f.irradiance[(side / 2) * side + side / 2] = [1.0; 3];
        f
    }

    fn input(&self) -> ScreenInput<'_> {
        ScreenInput {
            width: self.width,
            height: self.height,
            irradiance: &self.irradiance,
            depth: &self.depth,
            mask: &self.mask,
            mm_per_pixel: &self.mm,
        }
    }
}

/// One row of `kernels.csv`.
struct Row {
    material: String,
    method: String,
    placement: &'static str,
    passes: usize,
    taps_per_pixel: usize,
    seconds_all: f64,
    seconds_one: f64,
    threads: usize,
    rmse_exact2d: f64,
    rel_rmse_exact2d: f64,
    build_seconds: f64,
}

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

/// Every kernel on the `sphere` and `slab` scenes against their cached `exact` references.
fn world_space(ctx: &Context<'_>) -> Result<Vec<Vec<String>>, Error> {
    use super::scenes::{load_scenes, reference};
    use sss_render::integrators::separable::Separable;
    use sss_render::metrics::error_figures;
    use sss_render::progress::NoProgress;
    use sss_render::{RenderSettings, render};
    // Only the two scenes whose materials the table is about, if the run includes them.
    let names: Vec<String> = ctx
        .config
        .scenes
        .iter()
        .filter(|n| *n == "sphere" || *n == "slab")
        .cloned()
        .collect();
    let (scenes, _) = load_scenes(ctx, &names)?;
    let mut rows = Vec::new();
    for (scene, text) in &scenes {
        let r = reference(ctx, scene, text)?;
        let pixels: Vec<usize> = (0..r.coverage.len())
            .filter(|&i| r.coverage[i] > 0.0)
            .collect();
        for method in KernelMethod::ALL {
            let placements: &[bool] = match method {
                KernelMethod::Svd1
                | KernelMethod::Svd3
                | KernelMethod::Svd6
                | KernelMethod::Exact2d => &[false],
                _ => &[true, false],
            };
            for &importance in placements {
                let separable = Separable {
                    kernel: SeparableSettings {
                        kernel: method,
                        importance,
                        ..SeparableSettings::default()
                    },
                    ..Separable::default()
                };
                let settings = RenderSettings {
                    seed: ctx.config.seed,
                    ..RenderSettings::default()
                };
                let out = render(scene, &separable, &settings, &NoProgress)
                    .map_err(|e| Error(format!("{}: {method}: {e}", scene.name)))?;
                let f = error_figures(&out.subsurface, &r.subsurface, &pixels, 0.05);
                let sum = |img: &[Rgb]| -> f64 {
                    pixels.iter().map(|&i| img[i].iter().sum::<f64>()).sum()
                };
                let ratio = sum(&out.subsurface) / sum(&r.subsurface).max(1e-300);
                rows.push(vec![
                    scene.name.clone(),
                    method.name().to_string(),
                    if method == KernelMethod::Exact2d {
                        "full".to_string()
                    } else if importance {
                        "importance".to_string()
                    } else {
                        "uniform".to_string()
                    },
                    md_num(Some(out.seconds_total()), 3),
                    md_num(Some(f.rmse), 3),
                    md_num(Some(100.0 * f.rel_rmse), 3) + " %",
                    md_num(Some(ratio), 4),
                ]);
            }
        }
    }
    Ok(rows)
}

fn to_rgb(v: &[[f32; 3]]) -> Vec<Rgb> {
    v.iter()
        .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
        .collect()
}

/// The separable-kernel experiment.
pub struct KernelComparison;

impl Experiment for KernelComparison {
    fn name(&self) -> &'static str {
        "kernels"
    }

    fn run(&self, ctx: &Context<'_>) -> Result<Section, Error> {
        let cfg = ctx.config;
        let quick = cfg.quick;
        let materials: &[&str] = if quick {
            &["skin1", "marble"]
        } else {
            &["skin1", "marble", "ketchup", "skimmilk"]
        };
        let (fw, fh) = if quick { (480, 270) } else { (1920, 1080) };
        let big = Frame::edge(fw, fh);
        let test = Frame::edge(TEST_SIDE, TEST_SIDE);
        let all_threads = rayon::current_num_threads();
        let dir = cfg.out.join("kernels");
        std::fs::create_dir_all(&dir)
            .map_err(|e| Error(format!("cannot create {}: {e}", dir.display())))?;
        let e = |e: sss_render::Error| Error(e.to_string());
        let mut rows: Vec<Row> = Vec::new();
        let mut spectra = Vec::new();
        let mut curves: Vec<Series> = Vec::new();
        for (mi, &name) in materials.iter().enumerate() {
            (ctx.log)(&format!("kernels: {name}"));
            let medium = Medium::preset(name).map_err(|e| Error(e.to_string()))?;
            let model = make_model(ModelKind::BetterDipole, &medium);
            let k2 = Kernel2d::from_model(model.as_ref(), &Kernel2dSpec::default())
                .map_err(|e| Error(e.to_string()))?;
            let svd = svd::decompose(&k2).map_err(|e| Error(e.to_string()))?;
            let s = svd.spectrum(0);
            spectra.push(
                Series::line(
                    format!("{name} (red)"),
                    s.iter()
                        .take(16)
                        .enumerate()
                        .map(|(i, v)| ((i + 1) as f64, v / s[0].max(1e-300)))
                        .collect(),
                )
                .with_style(SeriesStyle::LineMarkers)
                .with_color(PALETTE[(mi + 1) % 8]),
            );
            let opts = FilterOptions::default();
            let exact =
                convolve2d::exact(&test.input(), &k2, &opts).map_err(|e| Error(e.to_string()))?;
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
                    let MaterialKernel::Separable(kernel) = build_kernel(model.as_ref(), &settings)
                        .map_err(|e| Error(format!("{name} {method}: {e}")))?
                    else {
                        continue;
                    };
                    let build_seconds = t.elapsed().as_secs_f64();
                    let out = screen_space::filter(&test.input(), &kernel, &opts)
                        .map_err(|e| Error(e.to_string()))?;
                    let (r, rel) = rmse(&out, &exact, &test.mask);
                    let seconds_all = timed_filter(&big, &kernel, all_threads)?;
                    let seconds_one = if all_threads > 1 {
                        timed_filter(&big, &kernel, 1)?
                    } else {
                        seconds_all
                    };
                    if importance
                        || matches!(
                            method,
                            KernelMethod::Svd1 | KernelMethod::Svd3 | KernelMethod::Svd6
                        )
                    {
                        points.push((seconds_all, rel));
                    }
                    if method == KernelMethod::Preintegrated && importance {
                        let w = TEST_SIDE as u32;
                        let exp = auto_exposure(&to_rgb(&exact));
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
                            &to_rgb(&exact),
                            exp,
                        )
                        .map_err(e)?;
                        write_png(
                            &dir.join(format!("{name}_edge_preintegrated.png")),
                            w,
                            w,
                            &to_rgb(&out),
                            exp,
                        )
                        .map_err(e)?;
                        let floor = to_rgb(&exact).iter().map(|p| p[0]).sum::<f64>()
                            / (w * w) as f64
                            * 0.01;
                        let values: Vec<Option<f64>> = out
                            .iter()
                            .zip(&exact)
                            .map(|(a, b)| {
                                Some(((a[0] - b[0]).abs() as f64) / (b[0] as f64).max(floor))
                            })
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
                        .map_err(|e| Error(e.to_string()))?;
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
            curves.push(
                Series::line(name, points)
                    .with_style(SeriesStyle::Markers)
                    .with_color(PALETTE[(mi + 1) % 8]),
            );
            // Point-light response with and without jitter (skin1 only shows the cross best).
            if mi == 0 {
                let p = Frame::point(TEST_SIDE);
                let k = match build_kernel(model.as_ref(), &SeparableSettings::default())
                    .map_err(|e| Error(e.to_string()))?
                {
                    MaterialKernel::Separable(k) => k,
                    MaterialKernel::Full(_) => unreachable!("pre-integrated is separable"),
                };
                for (label, jitter) in [("no_jitter", 0.0f32), ("jitter", 1.0)] {
                    let o = FilterOptions {
                        jitter_radius: jitter,
                        ..FilterOptions::default()
                    };
                    let out = screen_space::filter(&p.input(), &k, &o)
                        .map_err(|e| Error(e.to_string()))?;
                    let img = to_rgb(&out);
                    write_png(
                        &dir.join(format!("{name}_point_{label}.png")),
                        TEST_SIDE as u32,
                        TEST_SIDE as u32,
                        &img,
                        auto_exposure(&img),
                    )
                    .map_err(e)?;
                }
            }
        }
        // The production skin kernel of Table 2 (its own separable product is its definition):
        // cost only, with the pass and tap counts engines would ship.
        let skin = make_model(
            ModelKind::BetterDipole,
            &Medium::preset("skin1").map_err(|e| Error(e.to_string()))?,
        );
        let total: Rgb = std::array::from_fn(|c| skin.total_diffuse_reflectance(c));
        for (importance, placement) in [
            (true, TapPlacement::Importance(7)),
            (false, TapPlacement::Uniform(7)),
        ] {
            let k = artist::kernel(&artist::PRODUCTION, total, placement)
                .map_err(|e| Error(e.to_string()))?;
            let seconds_all = timed_filter(&big, &k, all_threads)?;
            let seconds_one = if all_threads > 1 {
                timed_filter(&big, &k, 1)?
            } else {
                seconds_all
            };
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
        let world = world_space(ctx)?;
        line_plot(
            &cfg.out.join("singular_values.png"),
            "Singular values of the discretised R_d (better dipole, red), relative to the first",
            "index",
            "s_i / s_1",
            &spectra,
            false,
            true,
        )
        .map_err(|e| Error(e.to_string()))?;
        line_plot(
            &cfg.out.join("kernel_error_vs_time.png"),
            &format!("Separable kernels: rel. RMSE vs exact 2D against {fw}x{fh} frame time ({all_threads} threads)"),
            "seconds per frame",
            "relative RMSE",
            &curves,
            true,
            true,
        )
        .map_err(|e| Error(e.to_string()))?;
        let mut csv = String::from(
            "material,method,placement,passes,taps_per_pixel,threads,seconds_frame,seconds_frame_1thread,rmse_exact2d,rel_rmse_exact2d,build_seconds,frame\n",
        );
        for r in &rows {
            let _ = writeln!(
                csv,
                "{},{},{},{},{},{},{},{},{},{},{},{fw}x{fh}",
                r.material,
                r.method,
                r.placement,
                r.passes,
                r.taps_per_pixel,
                r.threads,
                csv_num(Some(r.seconds_all)),
                csv_num(Some(r.seconds_one)),
                csv_num(Some(r.rmse_exact2d)),
                csv_num(Some(r.rel_rmse_exact2d)),
                csv_num(Some(r.build_seconds))
            );
        }
        write_atomic(&cfg.out.join("kernels.csv"), csv.as_bytes())?;
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
             with the full 127² kernel (better dipole), jitter 0.1. Images in `kernels/`, spectra in \
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
                &world
            )
        );
        let best = rows
            .iter()
            .filter(|r| r.material == "skin1" && r.method == "preintegrated" && r.placement == "importance")
            .map(|r| format!("skin1 pre-integrated, 7 importance taps: {} ms per frame, {} % rel. RMSE vs exact 2D", md_num(Some(r.seconds_all * 1e3), 3), md_num(Some(100.0 * r.rel_rmse_exact2d), 3)))
            .next()
            .unwrap_or_default();
        Ok(Section {
            title: "Separable kernels (Jimenez et al. 2015)".into(),
            summary: format!(
                "{best}. See the table below for every material, kernel and tap placement.\n"
            ),
            body,
        })
    }
}
