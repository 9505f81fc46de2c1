//! The screen-space pass's row-chunked fast path against its per-pixel form on the inputs of
//! every built-in scene (real silhouettes, depth layers, footprints that change across the
//! image, several objects and materials): within 10⁻⁵ relative per pixel and channel (with an
//! absolute floor of 10⁻⁶ of the channel's largest value, for pixels near zero; the reasons
//! are in `crates/separable/tests/screen_space_rows.rs`), at the scenes' resolution and at 4×
//! it (where kernels span many pixels and most chunks take the fast path).

use sss_render::frame::Frame;
use sss_render::integrators::separable::screen_buffers;
use sss_render::kernel_choice::{MaterialKernel, SeparableSettings, build_kernel, filter_options};
use sss_render::scene::{BUILTIN_SCENES, LoadOptions, builtin};
use sss_separable::NO_OBJECT;
use sss_separable::screen_space::{Evaluation, filter_into_with};

#[test]
fn built_in_scenes_filter_alike_on_both_paths() {
    let mut fast_seen = 0.0f64;
    for &(name, _) in BUILTIN_SCENES {
        let Ok(mut scene) = builtin(name, &LoadOptions::from_env()) else {
            eprintln!("skipping `{name}`: it does not load here (its mesh is not found)");
            continue;
        };
        for scale in [1, 4] {
            scene.camera.width *= scale;
            scene.camera.height *= scale;
            let frame = Frame::prepare(&scene, 3);
            // Any irradiance does: both paths filter the same input. A texture with detail
            // at every scale, so a misplaced tap changes the result.
            let irradiance: Vec<[f64; 3]> = frame
                .gbuffer
                .samples
                .iter()
                .map(|g| {
                    let t = (g.p.x * 13.0).sin() * (g.p.y * 7.0).cos() + (g.p.z * 29.0).sin();
                    [1.5 + t, 1.0 + 0.5 * t, 0.2 + 0.1 * t.abs()]
                })
                .collect();
            let screen = screen_buffers(&frame, &irradiance);
            let settings = SeparableSettings::default();
            let opts = filter_options(&settings, 3);
            let (w, h) = (frame.gbuffer.width as usize, frame.gbuffer.height as usize);
            for (m, sh) in frame.shading.iter().enumerate() {
                let Some(sh) = sh else { continue };
                let MaterialKernel::Separable(kernel) = build_kernel(sh.bssrdf(), &settings)
                    .unwrap_or_else(|e| panic!("{name}: kernel: {e}"))
                else {
                    panic!("{name}: the default kernel is separable");
                };
                // The integrator's conversion: the material's pixels, in mm.
                let buffers = screen.material_input(&scene, m, sh.units_per_mm, w, h);
                let (mask, mm, input) = (
                    &buffers.mask[..],
                    &buffers.mm_per_pixel[..],
                    buffers.input(),
                );
                let run = |evaluation| {
                    let mut out = vec![[0.0f32; 3]; w * h];
                    let fast = filter_into_with(
                        &input,
                        &kernel,
                        &opts,
                        &mut Default::default(),
                        &mut out,
                        evaluation,
                    )
                    .unwrap();
                    (out, fast)
                };
                let (rows, fast) = run(Evaluation::Rows);
                let (reference, _) = run(Evaluation::PerPixel);
                let magnitude: [f64; 3] = std::array::from_fn(|c| {
                    reference
                        .iter()
                        .map(|p| p[c].abs() as f64)
                        .fold(0.0, f64::max)
                });
                let mut worst = 0.0f64;
                let different = rows
                    .iter()
                    .zip(&reference)
                    .filter(|(a, b)| {
                        (0..3).any(|c| {
                            let (x, r) = (a[c] as f64, b[c] as f64);
                            let bound = 1e-5 * r.abs() + 1e-6 * magnitude[c];
                            worst = worst.max((x - r).abs() / bound.max(f64::MIN_POSITIVE));
                            let within = (x - r).abs() <= bound;
                            !within
                        })
                    })
                    .count();
                let shown = mask.iter().filter(|&&o| o != NO_OBJECT).count();
                let blurred = mm
                    .iter()
                    .zip(mask)
                    .filter(|&(&v, &o)| o != NO_OBJECT && 2.0 * kernel.support_mm as f32 / v >= 1.0)
                    .count();
                eprintln!(
                    "{name} ×{scale} material {m}: {w}×{h}, {shown} pixels shown, {blurred} \
                     blurred, support {:.2} mm, median mm/px {:.3}, fast path {:.1} % of \
                     their pixel passes, largest error {worst:.3} of the tolerance",
                    kernel.support_mm,
                    {
                        let mut v: Vec<f32> = mm
                            .iter()
                            .zip(mask)
                            .filter(|(_, o)| **o != NO_OBJECT)
                            .map(|(v, _)| *v)
                            .collect();
                        v.sort_by(f32::total_cmp);
                        v.get(v.len() / 2).copied().unwrap_or(0.0)
                    },
                    100.0 * fast * (w * h) as f64 / shown.max(1) as f64,
                );
                // Background pixels are never on the fast path: the share of the shown ones.
                let share = fast * (w * h) as f64 / shown.max(1) as f64;
                assert_eq!(different, 0, "{name} ×{scale} material {m}: pixels off");
                fast_seen = fast_seen.max(share);
            }
            scene.camera.width /= scale;
            scene.camera.height /= scale;
        }
    }
    // The comparison covered the fast path, not only its fallback.
    assert!(fast_seen > 0.4, "largest fast-path share {fast_seen}");
}
