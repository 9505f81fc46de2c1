//! Every kernel through the full render pipeline on built-in scenes, against the world-space
//! `exact` references the scenes experiment caches.

use super::*;
use crate::scenes::{load_scenes, reference};
use sss_render::integrators::separable::Separable;
use sss_render::metrics::error_figures;
use sss_render::progress::NoProgress;
use sss_render::{RenderSettings, render};

/// Every kernel on the `sphere` and `slab` scenes against their cached `exact` references.
pub(super) fn world_space(ctx: &Context<'_>) -> Result<Vec<Vec<String>>, Error> {
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
