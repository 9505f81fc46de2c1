//! Tests of the many-light comparison's plan, scoring and tables.

use super::*;
use sss_bssrdf::Rgb;
use sss_render::RenderOutput;
use sss_render::scene::builtin;

/// Area of every translucent triangle of a scene.
fn area(s: &Scene) -> f64 {
    let mut a = 0.0;
    for o in 0..s.objects.len() {
        if s.translucent(o).is_none() {
            continue;
        }
        let m = &s.objects[o].mesh;
        for t in &m.triangles {
            let [p, q, r] = t.map(|k| m.positions[k as usize]);
            a += 0.5 * (q - p).cross(r - p).length();
        }
    }
    a
}

#[test]
fn subdivision_keeps_the_surface_and_welds_midpoints() {
    let s = builtin("sphere", &LoadOptions::default()).unwrap();
    let (t0, a0) = (triangles(&s), area(&s));
    let o = (0..s.objects.len())
        .find(|&o| s.translucent(o).is_some())
        .unwrap();
    let v0 = s.objects[o].mesh.positions.len();
    let f = subdivide(&s, 2);
    assert_eq!(triangles(&f), 16 * t0);
    // Midpoints lie on the flat triangles: the area is unchanged to rounding.
    assert!((area(&f) - a0).abs() < 1e-9 * a0, "{} vs {a0}", area(&f));
    // A closed mesh: V − E + F = 2 before and after, so with E = 3F/2 each level adds
    // exactly E vertices (one per welded edge): V' = V + 3F/2.
    let m = &f.objects[o].mesh;
    let v1 = v0 + 3 * t0 / 2;
    let v2 = v1 + 3 * (4 * t0) / 2;
    assert_eq!(m.positions.len(), v2);
    assert_eq!(m.normals.len(), m.positions.len());
    assert!(m.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-9));
    // Opaque objects are left alone.
    for k in 0..s.objects.len() {
        if s.translucent(k).is_none() {
            assert_eq!(
                s.objects[k].mesh.triangles.len(),
                f.objects[k].mesh.triangles.len()
            );
        }
    }
}

/// erf (sss-separable's) against tabulated values (Abramowitz & Stegun Table 7.1), and the
/// calibrated accuracy: 95 % against an exact reference, 92.2 % against one whose error is ε/4
/// (1/√(1/1.96² + 1/16) = 1.761 standard deviations).
#[test]
fn calibrated_accuracy_is_95_percent_against_an_exact_reference() {
    for (x, want) in [
        (0.0, 0.0),
        (0.5, 0.520_499_878),
        (1.0, 0.842_700_793),
        (2.0, 0.995_322_265),
    ] {
        assert!((erf(x) - want).abs() < 2e-7, "erf({x}) = {}", erf(x));
        assert!((erf(-x) + want).abs() < 2e-7);
    }
    let r = Reference {
        pixels: vec![0, 1, 2],
        values: vec![[1.0; 3]; 3],
        rel_se: vec![0.0, 0.0, 0.02],
        ..Reference::default()
    };
    // ε = 10 %: all three resolve; two exact, one at 0.2 ε (erf(1.96/√2/√(1 + 0.2²·1.96²))).
    let third = erf(1.96 / std::f64::consts::SQRT_2 / (1.0 + (0.2f64 * 1.96).powi(2)).sqrt());
    let got = calibrated(&r, 0.1);
    assert!(
        (got - (2.0 * 0.950_004 + third) / 3.0).abs() < 1e-5,
        "{got}"
    );
    // ε = 4 %: the third does not resolve (0.02 > 0.01).
    assert!((calibrated(&r, 0.04) - 0.950_004).abs() < 1e-5);
    let quarter = Reference {
        rel_se: vec![0.025; 3],
        ..r.clone()
    };
    assert!(
        (calibrated(&quarter, 0.1) - 0.9218).abs() < 5e-4,
        "{}",
        calibrated(&quarter, 0.1)
    );
}

#[test]
fn accuracy_counts_relative_errors_below_eps_where_the_reference_resolves_it() {
    let r = Reference {
        pixels: vec![0, 1, 2, 3, 4],
        values: vec![[1.0; 3], [1.0; 3], [2.0; 3], [0.0; 3], [1.0; 3]],
        // The last pixel's reference is too noisy for ε = 5 % (0.02 > 0.05/4).
        rel_se: vec![0.0, 0.0, 0.0125, 0.0, 0.02],
        ..Reference::default()
    };
    let px = |v: f64| PixelResult {
        subsurface: [v; 3],
        ..PixelResult::default()
    };
    // 1.04 (4 %), 0.9 (10 %), 2.06 (3 %); the black reference pixel and the unresolved
    // one are not scored.
    let out = [px(1.04), px(0.9), px(2.06), px(0.5), px(1.0)];
    let got = score(&out, &r, 0.05);
    assert_eq!(got.scored, 3);
    assert!((got.accuracy - 2.0 / 3.0).abs() < 1e-12);
    let want = ((0.04f64.powi(2) + 0.1f64.powi(2) + 0.06f64.powi(2) + 0.25) / 5.0).sqrt();
    assert!((got.rmse - want).abs() < 1e-12, "{} vs {want}", got.rmse);
    // Σ(Î − I) = 0.04 − 0.1 + 0.06 + 0.5 + 0 over Σ I = 5, every pixel counted; its
    // standard error √Σ(Î − I)² / Σ I.
    assert!((got.bias - 0.1).abs() < 1e-12, "{}", got.bias);
    let d2 = 0.04f64.powi(2) + 0.1f64.powi(2) + 0.06f64.powi(2) + 0.25;
    assert!(
        (got.bias_se - d2.sqrt() / 5.0).abs() < 1e-12,
        "{}",
        got.bias_se
    );
    // At ε = 10 % the last pixel resolves (0.02 ≤ 0.025) and 0.9 is not below 10 %.
    let got = score(&out, &r, 0.1);
    assert_eq!(got.scored, 4);
    assert!((got.accuracy - 3.0 / 4.0).abs() < 1e-12);
    // Pooled over two runs of different sizes: weighted by estimates.
    let row = |accuracy: f64, pixels: usize| Row {
        scene: "s",
        experiment: "accuracy",
        method: OURS,
        selection: "bssrdf",
        eps: 0.05,
        points: 0,
        vpls: 1,
        triangles: 1,
        seed: 1,
        seconds: 0.0,
        pixels,
        mean_triplets: 0.0,
        accuracy,
        rmse: 0.0,
        bias: 0.0,
        bias_se: 0.0,
        capped: 0,
        floored: 0,
    };
    let (r1, r2) = (row(1.0, 30), row(0.5, 10));
    let (a, se, n) = pooled(&[&r1, &r2]);
    assert_eq!(n, 40);
    assert!((a - 35.0 / 40.0).abs() < 1e-12);
    assert!((se - (a * (1.0 - a) / 40.0).sqrt()).abs() < 1e-12);
}

/// Table 1 and the goal line from hand-made rows: ours at ε = 2 % takes 2 s for RMSE 0.01
/// (mean of two streams); EELC-IS's sweep RMSE = 0.1 t^−½ crosses 0.01 at 100 s (50×,
/// met); MDLC-IS stops at 0.02 after 16 s (not reached, > 8×, ≈ 32× extrapolated: 4× the
/// time per halving of the error, 16 s × 4 = 64 s); EELC-uniform starts below the target.
#[test]
fn table1_reads_equal_quality_and_time_off_the_sweeps() {
    let mut p = plan(false);
    p.eps = vec![0.05, 0.02];
    let row = |method: &'static str, experiment, eps, points, seed, seconds, rmse| Row {
        scene: "s",
        experiment,
        method,
        selection: "-",
        eps,
        points,
        vpls: 1,
        triangles: 1,
        seed,
        seconds,
        pixels: 10,
        mean_triplets: 1.0,
        accuracy: 0.9,
        rmse,
        bias: 0.0,
        bias_se: 0.0,
        capped: 0,
        floored: 0,
    };
    let mut rows = vec![
        row(OURS, "accuracy", 0.05, 0, 1, 0.5, 0.04),
        row(OURS, "accuracy", 0.02, 0, 1, 1.5, 0.008),
        row(OURS, "accuracy", 0.02, 0, 2, 2.5, 0.012),
    ];
    for (n, t) in [(64, 1.0), (256, 16.0), (1024, 400.0)] {
        rows.push(row("eelc-is", "quality", 0.02, n, 1, t, 0.1 / f64::sqrt(t)));
    }
    // Given out of order: the sweep is read fewest points first.
    rows.push(row("mdlc-is", "quality", 0.02, 256, 1, 16.0, 0.02));
    rows.push(row("mdlc-is", "quality", 0.02, 64, 1, 4.0, 0.04));
    rows.push(row("eelc-uniform", "quality", 0.02, 64, 1, 3.0, 0.005));
    let (t_ours, e_ours) = ours_at_fixed(&rows, "s", &p).unwrap();
    assert!((t_ours - 2.0).abs() < 1e-12 && (e_ours - 0.01).abs() < 1e-12);
    let (r, x) = equal_quality(&rows, "s", "eelc-is", 0.01);
    let Some(Reach::At(t)) = r else {
        panic!("{r:?}")
    };
    assert!((t - 100.0).abs() < 1e-9, "{t}");
    assert_eq!(x, None);
    let (r, x) = equal_quality(&rows, "s", "mdlc-is", 0.01);
    assert_eq!(r, Some(Reach::NotReached(16.0)));
    assert!((x.unwrap() - 64.0).abs() < 1e-9);
    assert_eq!(
        reach_cells(r, x, 2.0),
        [
            "not reached (> 16.0; ≈ 64.0 extrapolated)".to_string(),
            "> 8.00× (≈ 32.0×)".to_string()
        ]
    );
    let (r, _) = equal_quality(&rows, "s", "eelc-uniform", 0.01);
    assert_eq!(r, Some(Reach::AtMost(3.0)));
    let refs = vec![("s", Reference::default(), 1)];
    let goal = goal_line(&rows, &refs, &p);
    assert!(goal.contains("s 50.0× (met)"), "{goal}");
    let t = table1(&rows, &refs, &p);
    // Equal time: EELC-IS at ours' 2 s is 0.1/√2.
    let want = md_num(Some(0.1 / 2f64.sqrt()), 3);
    assert!(t.contains(&want), "{want} in {t}");
    assert!(t.contains("outside its runs (4.00–16.0 s)"), "{t}");
    assert!(t.contains("≤ 3.00 (its cheapest run)"), "{t}");
}

/// Every column of the experiment's CSV is documented in `docs/compare.md`.
#[test]
fn every_csv_column_is_documented() {
    assert_eq!(crate::output::undocumented(&csv(&[])), Vec::<String>::new());
}

/// A window is a centred crop of the 1080p frame: every window pixel's ray is the ray through
/// the same point of the 1080-row frame (a 1440 × 1080 frame here, the head's 4:3), pixel
/// for pixel, so its pixels subtend what the frame's do.
#[test]
fn a_window_is_the_centre_of_the_1080p_frame() {
    use sparse::{WINDOW_ROWS, window};
    use sss_render::camera::CameraFrame;
    let s = builtin("sphere", &LoadOptions::default()).unwrap();
    let mut full = s.camera.clone();
    full.width = 1440;
    full.height = WINDOW_ROWS;
    let big = CameraFrame::new(&full);
    for (w, h) in [(64, 64), (128, 96), (33, 17)] {
        let win = window(&s, WINDOW_ROWS, w, h);
        assert_eq!((win.camera.width, win.camera.height), (w, h));
        assert_eq!(win.camera.pixel_samples, 1);
        let small = CameraFrame::new(&win.camera);
        let rel = (small.pixel_angle() / big.pixel_angle() - 1.0).abs();
        assert!(rel < 1e-12, "{w}x{h}: pixel angle off by {rel}");
        let (ox, oy) = (0.5 * f64::from(1440 - w), 0.5 * f64::from(WINDOW_ROWS - h));
        for (x, y) in [
            (0.0, 0.0),
            (0.5, 0.5),
            (f64::from(w), 3.25),
            (7.5, f64::from(h)),
        ] {
            let a = small.direction(x, y);
            let b = big.direction(x + ox, y + oy);
            assert!(
                (a - b).length() < 1e-12,
                "{w}x{h} at ({x}, {y}): {a} vs {b}"
            );
        }
    }
}

/// A render's scores on the subset, by hand: within ε, within the interval, reconstructed or
/// estimated, and the pixels whose reference cannot resolve ε left out. The counts differ from
/// their complements (2 of 3, 3 of 4), so a flipped comparison shows.
#[test]
fn sparse_scores_count_by_hand() {
    use sparse::{SparseRow, score_render};
    // Five pixels of reference luminance 2 (grey), relative standard errors 0 but the last,
    // 0.05, which does not resolve ε = 2 % and is not scored.
    let r = Reference {
        pixels: vec![0, 1, 2, 3, 4],
        values: vec![[2.0; 3]; 5],
        rel_se: vec![0.0, 0.0, 0.0, 0.0, 0.05],
        ..Reference::default()
    };
    let grey = |v: f64| [v; 3];
    let layer =
        |name: &'static str, pixels: Vec<Rgb>| sss_render::integrators::Layer { name, pixels };
    let stat = |name: &'static str, value: f64| sss_render::integrators::Stat { name, value };
    // ε × value = 0.04. Pixel 0 estimated at 2.02 (within ε). Reconstructed: 1 at 2.06 with
    // interval 0.1 (outside ε, inside its interval); 2 at 1.98 with interval 0.01 (inside ε,
    // outside its interval); 3 at 2.005 with interval 0.02 (inside both); 4 not scored.
    let out = RenderOutput {
        method: "sparse-manylight",
        width: 5,
        height: 1,
        subsurface: vec![grey(2.02), grey(2.06), grey(1.98), grey(2.005), grey(3.0)],
        total: vec![grey(0.0); 5],
        std_error: None,
        coverage: vec![1.0; 5],
        alpha: vec![1.0; 5],
        stages: Vec::new(),
        stats: vec![stat("pixels_reconstructed", 4.0), stat("triplets", 500.0)],
        irradiance_samples: 0,
        irradiance_left_out: 0,
        spacing: Vec::new(),
        layers: vec![
            layer(
                "estimated",
                vec![grey(1.0), grey(0.0), grey(0.0), grey(0.0), grey(0.0)],
            ),
            layer(
                "interval",
                vec![grey(0.04), grey(0.1), grey(0.01), grey(0.02), grey(0.01)],
            ),
        ],
        warnings: Vec::new(),
    };
    let row = score_render(
        &out,
        &r,
        SparseRow {
            eps: 0.02,
            translucent: 5,
            ..SparseRow::default()
        },
    );
    assert_eq!(row.reconstructed, 4);
    assert!((row.triplets_per_pixel - 100.0).abs() < 1e-12);
    assert_eq!(row.scored, 4);
    // Within 2 % of 2: pixels 0, 2 and 3 of the four scored.
    assert!((row.accuracy - 0.75).abs() < 1e-12, "{}", row.accuracy);
    assert_eq!(row.scored_reconstructed, 3);
    assert!((row.accuracy_reconstructed - 2.0 / 3.0).abs() < 1e-12);
    assert!((row.coverage_reconstructed - 2.0 / 3.0).abs() < 1e-12);
    // The image mean over all five: (2.02 + 2.06 + 1.98 + 2.005 + 3) / 10 − 1.
    assert!(
        (row.bias - (11.065 / 10.0 - 1.0)).abs() < 1e-12,
        "{}",
        row.bias
    );
}

/// Every column of the sparse experiment's CSVs is documented in `docs/compare.md`.
#[test]
fn every_sparse_csv_column_is_documented() {
    use crate::output::undocumented;
    assert_eq!(undocumented(&sparse::sparse_csv(&[])), Vec::<String>::new());
    assert_eq!(undocumented(&sparse::cells_csv(&[])), Vec::<String>::new());
}
