//! The subset reference: `exact` on a seeded
//! uniform random subset of the pixels with translucent coverage, and the estimate of an
//! image's MSE from it, against the full-image figures.

use sss_render::frame::Frame;
use sss_render::integrators::exact::{Exact, shade_subset, translucent_pixels};
use sss_render::irradiance::IrradianceSettings;
use sss_render::metrics::{error_figures, subset_error, subset_pixels};
use sss_render::progress::NoProgress;
use sss_render::scene::{LoadOptions, Scene, builtin};
use sss_render::{RenderSettings, render};

/// The built-in sphere at 48×36.
fn scene() -> Scene {
    let mut s = builtin("sphere", &LoadOptions::default()).unwrap();
    s.camera.width = 48;
    s.camera.height = 36;
    s
}

fn exact(spacing: f64) -> Exact {
    Exact {
        irradiance: IrradianceSettings {
            spacing_mfp: spacing,
            ..IrradianceSettings::default()
        },
    }
}

#[test]
fn subset_estimate_agrees_with_the_full_image() {
    let scene = scene();
    let settings = RenderSettings::default();
    let reference_method = exact(1.0);
    let reference = render(&scene, &reference_method, &settings, &NoProgress).unwrap();
    // The image scored: coarser samples, so it has an error to estimate.
    let image = render(&scene, &exact(4.0), &settings, &NoProgress).unwrap();
    let pixels = reference.translucent_pixels();
    let full = error_figures(&image.subsurface, &reference.subsurface, &pixels, 0.05);
    let full_mse = full.rmse * full.rmse;

    // The subset reference: the same frame (seed), only a quarter of the pixels shaded.
    let frame = Frame::prepare(&scene, settings.seed);
    assert_eq!(translucent_pixels(&frame), pixels);
    let n = pixels.len();
    let subset = subset_pixels(&pixels, n / 4, 3);
    let values = shade_subset(&frame, &reference_method.irradiance, &subset).unwrap();
    for (&i, v) in subset.iter().zip(&values) {
        for c in 0..3 {
            let r = reference.subsurface[i][c];
            assert!((v[c] - r).abs() <= 1e-12 * r, "pixel {i}: {v:?} vs {r}");
        }
    }
    let e = subset_error(&image.subsurface, &subset, &values, n).unwrap();
    eprintln!(
        "{n} pixels: full MSE {full_mse:.4e}; subset of {}: {:.4e} ± {:.2e}; RMSE {:.4e} vs \
         {:.4e} ± {:.2e}",
        subset.len(),
        e.mse,
        e.mse_se,
        full.rmse,
        e.rmse,
        e.rmse_se
    );
    assert!(e.mse_se > 0.0 && e.mse_se < 0.5 * e.mse, "{e:?}");
    assert!(
        (e.mse - full_mse).abs() <= 3.0 * e.mse_se,
        "{e:?} vs {full_mse}"
    );
    assert!(
        (e.rmse - full.rmse).abs() <= 3.0 * e.rmse_se,
        "{e:?} vs {}",
        full.rmse
    );

    // The standard error is honest: over 200 subsets (reference values from the full
    // render) the estimates scatter about the full value as their standard errors say.
    let seeds = 200;
    let (mut within1, mut within2, mut mean) = (0, 0, 0.0);
    for seed in 0..seeds {
        let s = subset_pixels(&pixels, n / 4, 100 + seed);
        let r: Vec<_> = s.iter().map(|&i| reference.subsurface[i]).collect();
        let e = subset_error(&image.subsurface, &s, &r, n).unwrap();
        let z = (e.mse - full_mse) / e.mse_se;
        within1 += (z.abs() <= 1.0) as usize;
        within2 += (z.abs() <= 2.0) as usize;
        mean += e.mse / seeds as f64;
    }
    let (f1, f2) = (within1 as f64 / seeds as f64, within2 as f64 / seeds as f64);
    eprintln!("{seeds} subsets: {f1:.3} within 1 SE, {f2:.3} within 2 SE; mean {mean:.4e}");
    // Normal: 0.683 and 0.954; skewed squared errors bring them down a little.
    assert!(f1 > 0.55 && f2 > 0.85, "{f1} within 1 SE, {f2} within 2 SE");
    // Unbiased: the mean of 200 estimates is within 4 of its standard errors of the full
    // value (the estimates' spread is about one standard error).
    assert!(
        (mean - full_mse).abs() <= 4.0 * e.mse_se / (seeds as f64).sqrt(),
        "{mean}"
    );

    // Every pixel: the full value to rounding, with no sampling error.
    let all = shade_subset(&frame, &reference_method.irradiance, &pixels).unwrap();
    let e = subset_error(&image.subsurface, &pixels, &all, n).unwrap();
    assert!(
        (e.mse - full_mse).abs() <= 1e-12 * full_mse,
        "{e:?} vs {full_mse}"
    );
    assert_eq!(e.mse_se, 0.0);

    // A pixel past the image is an error.
    let past = scene.camera.width as usize * scene.camera.height as usize;
    assert!(shade_subset(&frame, &reference_method.irradiance, &[past]).is_err());
}
