//! The screen-space filter: silhouettes, jitter, footprint, determinism, bad input.

use crate::common;

use crate::common::Frame;
use sss_separable::screen_space::{self, FilterOptions, rotation_angle};
use sss_separable::{
    NO_OBJECT, SeparableError, SeparableKernel, TapPlacement, convolve2d, preintegrated,
};

#[test]
fn no_energy_crosses_a_silhouette() {
    // Two objects side by side: left (id 1) lit, right (id 2) dark.
    let mut f = Frame::flat(60, 40, 0.3);
    for y in 0..f.height {
        for x in 0..f.width {
            let i = y * f.width + x;
            f.mask[i] = if x < 30 { 1 } else { 2 };
            f.irradiance[i] = if x < 30 { [1.0, 0.8, 0.5] } else { [0.0; 3] };
        }
    }
    for jitter in [0.0, 0.3, 1.0] {
        let opts = FilterOptions {
            jitter_radius: jitter,
            ..Default::default()
        };
        for (name, kernel) in common::screen_kernels() {
            let out = screen_space::filter(&f.input(), &kernel, &opts).unwrap();
            let total = kernel.total_weight();
            for y in 0..f.height {
                for x in 0..f.width {
                    let p = out[y * f.width + x];
                    if x >= 30 {
                        assert_eq!(p, [0.0; 3], "{name} jitter {jitter} leaked at ({x},{y})");
                    } else {
                        // The lit object keeps its energy (renormalised by the taps kept).
                        let e = [1.0, 0.8, 0.5];
                        for c in 0..3 {
                            let want = e[c] * total[c];
                            assert!(
                                ((p[c] as f64 - want) / want).abs() < 1e-4,
                                "{name} ({x},{y}) ch {c}: {} vs {want}",
                                p[c]
                            );
                        }
                    }
                }
            }
        }
    }
    // The exact 2D reference follows the same rule.
    let m = common::model("skin1");
    let k = common::kernel2d(m.as_ref(), 31);
    let exact = convolve2d::exact(&f.input(), &k, &FilterOptions::default()).unwrap();
    for y in 0..f.height {
        for x in 30..f.width {
            assert_eq!(exact[y * f.width + x], [0.0; 3]);
        }
    }
}

#[test]
fn a_depth_jump_stops_light_and_background_stays_black() {
    // One object id, but the right half is 100 mm further away: a silhouette in depth. The
    // bottom rows are background.
    let mut f = Frame::flat(60, 40, 0.3);
    for y in 0..f.height {
        for x in 0..f.width {
            let i = y * f.width + x;
            if x >= 30 {
                f.depth[i] = 1100.0;
            }
            if y >= 35 {
                f.mask[i] = NO_OBJECT;
            }
            f.irradiance[i] = if x < 30 { [1.0; 3] } else { [0.0; 3] };
        }
    }
    for (name, kernel) in common::screen_kernels() {
        assert!(kernel.support_mm < 100.0);
        let out = screen_space::filter(&f.input(), &kernel, &FilterOptions::default()).unwrap();
        for y in 0..f.height {
            for x in 0..f.width {
                if x >= 30 || y >= 35 {
                    assert_eq!(out[y * f.width + x], [0.0; 3], "{name} ({x},{y})");
                }
            }
        }
    }
}

/// The cross pattern's strength: on circles of radius 2..20 pixels around `centre`, the
/// amplitude of the cos 4θ component of the (bilinearly interpolated) response relative to
/// its mean, averaged over the radii. A radial response gives ~0; a "+" or "×" shape does
/// not. Noise from jitter mostly averages out over the 720 angles.
fn anisotropy(out: &[[f32; 3]], w: usize, centre: usize) -> f64 {
    let at = |x: f64, y: f64| -> f64 {
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let v = |i: f64, j: f64| out[j as usize * w + i as usize][0] as f64;
        (1.0 - fx) * (1.0 - fy) * v(x0, y0)
            + fx * (1.0 - fy) * v(x0 + 1.0, y0)
            + (1.0 - fx) * fy * v(x0, y0 + 1.0)
            + fx * fy * v(x0 + 1.0, y0 + 1.0)
    };
    let radii = 2..=20;
    let count = radii.clone().count() as f64;
    radii
        .map(|r| {
            let (mut mean, mut c4) = (0.0, 0.0);
            let m = 720;
            for i in 0..m {
                let t = std::f64::consts::TAU * i as f64 / m as f64;
                let v = at(
                    centre as f64 + r as f64 * t.cos(),
                    centre as f64 + r as f64 * t.sin(),
                );
                mean += v;
                c4 += v * (4.0 * t).cos();
            }
            2.0 * c4.abs() / mean
        })
        .sum::<f64>()
        / count
}

#[test]
fn rotation_jitter_removes_the_cross_pattern() {
    // A point light on a flat object: a rank-1 kernel responds with a cross (its axes carry
    // a(r)a(0), its diagonals a(r/√2)²); jittered axes spread it over all directions.
    let m = common::model("skin1");
    let k = common::kernel2d(m.as_ref(), 63);
    let kernel = preintegrated::kernel(&k, TapPlacement::Grid).unwrap();
    let w = 81;
    let c = w / 2;
    // Kernel radius ≈ 14 mm over ≈ 24 pixels; kernel cells (0.45 mm) finer than pixels, so
    // the point is not aliased.
    let mut f = Frame::flat(w, w, 0.6);
    f.irradiance[c * w + c] = [1.0; 3];
    let run = |jitter: f32| {
        let opts = FilterOptions {
            jitter_radius: jitter,
            ..Default::default()
        };
        screen_space::filter(&f.input(), &kernel, &opts).unwrap()
    };
    let none = anisotropy(&run(0.0), w, c);
    let full = anisotropy(&run(1.0), w, c);
    let exact = anisotropy(
        &convolve2d::exact(&f.input(), &k, &FilterOptions::default()).unwrap(),
        w,
        c,
    );
    eprintln!("anisotropy: no jitter {none}, full jitter {full}, exact 2D {exact}");
    assert!(full < 0.5 * none, "jitter {full} vs none {none}");
    assert!(
        exact < full,
        "the radial kernel {exact} should be the most isotropic"
    );
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let mut f = Frame::flat(70, 50, 0.2);
    f.set_irradiance(common::hash01);
    let opts = FilterOptions {
        jitter_radius: 0.5,
        seed: 7,
        ..Default::default()
    };
    for (name, kernel) in common::screen_kernels() {
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| screen_space::filter(&f.input(), &kernel, &opts).unwrap())
        };
        assert_eq!(run(1), run(2), "{name}");
    }
    // The rotation hash is a pure function of (x, y, seed).
    assert_eq!(rotation_angle(3, 4, 5), rotation_angle(3, 4, 5));
    assert_ne!(rotation_angle(3, 4, 5), rotation_angle(3, 4, 6));
    assert!((0..1000).all(|i| (0.0..std::f32::consts::TAU).contains(&rotation_angle(i, 2 * i, 1))));
}

#[test]
fn sub_pixel_kernels_skip_the_blur_and_bad_pixels_stay_finite() {
    let (_, kernel) = common::screen_kernels().remove(0);
    let total = kernel.total_weight();
    // 2·support / mm_per_pixel < 1 pixel: output = irradiance × total reflectance.
    let mut f = Frame::flat(8, 6, (4.0 * kernel.support_mm) as f32);
    f.set_irradiance(|x, y| (x + 2 * y) as f32);
    // Degenerate pixel sizes: treated as unblurred, never NaN.
    f.mm_per_pixel[3] = 0.0;
    f.mm_per_pixel[4] = f32::NAN;
    f.mm_per_pixel[5] = f32::INFINITY;
    f.depth[6] = f32::NAN;
    let out = screen_space::filter(&f.input(), &kernel, &FilterOptions::default()).unwrap();
    for (i, p) in out.iter().enumerate() {
        let e = f.irradiance[i][0] as f64;
        for c in 0..3 {
            assert!(p[c].is_finite());
            assert!(
                (p[c] as f64 - e * total[c]).abs() <= 1e-5 * (1.0 + e),
                "{i} {c}"
            );
        }
    }
}

#[test]
fn bad_input_is_an_error() {
    let (_, kernel) = common::screen_kernels().remove(0);
    let f = Frame::flat(8, 6, 0.1);
    let mut input = f.input();
    input.depth = &f.depth[..10];
    assert!(matches!(
        screen_space::filter(&input, &kernel, &FilterOptions::default()),
        Err(SeparableError::BufferSize { what: "depth", .. })
    ));
    let bad = FilterOptions {
        jitter_radius: -1.0,
        ..Default::default()
    };
    assert!(screen_space::filter(&f.input(), &kernel, &bad).is_err());
    let empty = SeparableKernel::default();
    assert!(screen_space::filter(&f.input(), &empty, &FilterOptions::default()).is_err());
    let mut out = vec![[0.0; 3]; 3];
    assert!(
        screen_space::filter_into(
            &f.input(),
            &kernel,
            &FilterOptions::default(),
            &mut Default::default(),
            &mut out
        )
        .is_err()
    );
}

/// The exact 2D reference's rule for signed kernels: where a silhouette drops cells, the
/// dropped weight takes the centre's value, so a constant irradiance E comes out as E × the
/// kernel's total on both sides of the silhouette. The kernel is a difference of Gaussians
/// (a positive core, a negative ring: it changes sign, so the renormalising branch is not
/// taken) in every channel.
#[test]
fn exact_reference_keeps_a_constant_under_a_signed_kernel_at_a_silhouette() {
    let dog = |x: f64, y: f64| {
        let r2 = x * x + y * y;
        let g = |s: f64| (-r2 / (2.0 * s * s)).exp() / (2.0 * std::f64::consts::PI * s * s);
        [1.5 * g(0.5) - 0.5 * g(1.5); 3]
    };
    let k = sss_separable::Kernel2d::from_density(21, 0.4, 4, dog).unwrap();
    assert!(k.mass[0].iter().any(|m| *m < 0.0) && k.mass[0].iter().any(|m| *m > 0.0));
    let mut f = Frame::flat(40, 12, 0.3);
    for y in 0..f.height {
        for x in 20..f.width {
            f.mask[y * f.width + x] = 1;
        }
    }
    let e = [1.0f32, 0.8, 0.5];
    for p in f.irradiance.iter_mut() {
        *p = e;
    }
    let out = convolve2d::exact(&f.input(), &k, &FilterOptions::default()).unwrap();
    for y in 0..f.height {
        for x in 0..f.width {
            for c in 0..3 {
                let want = e[c] as f64 * k.total[c];
                let got = out[y * f.width + x][c] as f64;
                assert!(
                    (got - want).abs() < 1e-5 * want.abs(),
                    "({x},{y}) ch {c}: {got} vs {want}"
                );
            }
        }
    }
}
