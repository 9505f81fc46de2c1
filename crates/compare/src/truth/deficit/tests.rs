use super::measure::{mean_over, ratio, relative_se, samples_for};
use super::report::{DeficitRow, apportion, deficit_csv, flat_limit, flux_ratio, section, shares};
use super::setups::FlatLight;
use super::*;

fn mean(m: Rgb, se: Rgb) -> Mean {
    Mean {
        mean: m,
        se,
        spp: 1,
        seconds: 1.0,
    }
}

/// A mean over pixels with independent errors: the variances add, so the standard error of
/// the mean of n pixels of error s is s/√n.
#[test]
fn the_means_error_adds_the_pixels_variances() {
    let image = vec![
        [1.0, 2.0, 3.0],
        [3.0, 2.0, 1.0],
        [100.0; 3],
        [2.0, 2.0, 2.0],
    ];
    let se = vec![[0.3, 0.4, 0.0], [0.4, 0.3, 0.0], [9.0; 3], [0.0, 0.0, 1.2]];
    let (m, s) = mean_over(&image, &se, &[0, 1, 3]);
    assert_eq!(m, [2.0, 2.0, 2.0]);
    // √(0.09 + 0.16)/3 = 0.5/3; √1.44/3 = 0.4.
    assert!((s[0] - 0.5 / 3.0).abs() < 1e-15 && (s[1] - 0.5 / 3.0).abs() < 1e-15);
    assert!((s[2] - 0.4).abs() < 1e-15);
    // The worst channel: blue, 0.4 / 2.
    assert!((relative_se(m, s) - 0.2).abs() < 1e-15);
    assert_eq!(relative_se([0.0; 3], [1.0; 3]), 0.0);
    // A channel below 10⁻³ of the largest is left out (ketchup's blue).
    assert!((relative_se([1.0, 0.5, 1e-4], [0.01, 0.01, 1.0]) - 0.02).abs() < 1e-15);
}

/// The samples a target asks for grow with the square of the pilot's error over it, within
/// the pilot's and the cap.
#[test]
fn samples_follow_one_over_the_square_root() {
    assert_eq!(samples_for(16, 0.04, 0.01, 10_000), 256);
    assert_eq!(samples_for(16, 0.04, 0.01, 100), 100);
    assert_eq!(samples_for(16, 0.001, 0.01, 100), 16);
    assert_eq!(samples_for(16, 0.0, 0.01, 100), 16);
    // A pilot that measured nothing usable asks for the cap.
    assert_eq!(samples_for(16, f64::INFINITY, 0.01, 100), 100);
}

/// The ratio's error to first order, by hand: (2 ± 0.1)/(4 ± 0.2) = 0.5 ± 0.5·√(0.05² + 0.05²).
#[test]
fn a_ratios_error_by_hand() {
    let q = ratio(
        &mean([2.0, 0.0, 1.0], [0.1, 0.3, 0.0]),
        &mean([4.0, 2.0, 0.0], [0.2, 0.0, 0.0]),
    );
    let (r, s) = q[0].unwrap();
    assert!((r - 0.5).abs() < 1e-15);
    assert!((s - 0.5 * (2.0f64 * 0.0025).sqrt()).abs() < 1e-15);
    // A zero numerator keeps its own error; a zero denominator has no ratio.
    assert_eq!(q[1], Some((0.0, 0.15)));
    assert_eq!(q[2], None);
}

fn row(group: &'static str, kind: Kind, value: f64, model: Rgb, truth: Rgb) -> DeficitRow {
    DeficitRow {
        setup: Setup {
            group,
            param: "p",
            value,
            medium: super::super::plan::SKIN1,
            kind,
        },
        truth: mean(truth, [0.0; 3]),
        single: mean([0.1; 3], [0.0; 3]),
        direct: None,
        model: mean(model, [0.0; 3]),
        albedo: mean(model, [0.0; 3]),
        pixels: 4,
    }
}

fn scaled(scale: f64) -> Kind {
    Kind::Scaled {
        scene: "sphere10",
        text: super::super::plan::SPHERE10,
        lighting: super::super::plan::Lighting::Quad,
        scale,
    }
}

/// The flat limit of D = D∞ − a/s from two scales is D∞ exactly.
#[test]
fn the_flat_limit_extrapolates_one_over_the_scale() {
    let d = |s: f64| 0.95 - 2.3 / s;
    assert!((flat_limit((16.0, d(16.0)), (64.0, d(64.0))) - 0.95).abs() < 1e-14);
    assert!((flat_limit((4.0, d(4.0)), (16.0, d(16.0))) - 0.95).abs() < 1e-14);
    // Unordered or equal scales give the larger scale's value.
    assert_eq!(flat_limit((16.0, 0.5), (16.0, 0.7)), 0.7);
}

/// The three factors multiply back to the total, and each is the ratio of the rows the
/// definition names (numbers chosen so every factor differs).
#[test]
fn the_factors_multiply_to_the_deficit() {
    let flat = Kind::Flat {
        light: FlatLight::Sun(0.0),
        view: 0.0,
        thickness: 100.0,
    };
    let rows = vec![
        row("incidence", flat, 0.0, [0.9, 0.95, 1.0], [1.0; 3]),
        row("incidence", flat, 60.0, [0.5; 3], [1.0; 3]),
        row("sphere-quad", scaled(1.0), 10.0, [0.6, 0.76, 0.5], [1.0; 3]),
        row("sphere-quad", scaled(4.0), 40.0, [0.1; 3], [1.0; 3]),
        row(
            "sphere-quad",
            scaled(16.0),
            160.0,
            [0.7, 0.7, 0.7],
            [1.0; 3],
        ),
        row(
            "sphere-quad",
            scaled(64.0),
            640.0,
            [0.8, 0.8, 2.0],
            [2.0; 3],
        ),
    ];
    let a = apportion(&rows);
    assert_eq!(a.len(), 1);
    let a = &a[0];
    assert_eq!(a.scales, (16.0, 64.0));
    assert_eq!(a.total, [0.6, 0.76, 0.5]);
    assert_eq!(a.largest, [0.4, 0.4, 1.0]);
    // The flat limit from 16 and 64: D₆₄ + (D₆₄ − D₁₆)/3.
    let flat = [0.4 - 0.1, 0.4 - 0.1, 1.0 + 0.1];
    for c in 0..3 {
        assert!((a.flat[c] - flat[c]).abs() < 1e-12);
        assert!((a.size[c] - a.total[c] / flat[c]).abs() < 1e-12);
        assert!((a.angles[c] - flat[c] / [0.9, 0.95, 1.0][c]).abs() < 1e-12);
        assert!((a.size[c] * a.angles[c] * a.profile[c] - a.total[c]).abs() < 1e-12);
    }
    // A convex set-up trades no light: its interreflection factor is 1.
    assert_eq!(a.interreflection, [1.0; 3]);
    // Shares of ln total add to 1, and the profile's blue share is 0 (ln 1).
    let s = shares(a);
    for c in 0..3 {
        let sum: f64 = (0..4).map(|k| s[k][c].unwrap()).sum();
        assert!((sum - 1.0).abs() < 1e-12, "{c}: {sum}");
    }
    assert_eq!(s[2][2], Some(0.0));
    // Without the head-on row, or with one larger scale only, there is nothing to apportion.
    assert!(apportion(&rows[1..]).is_empty());
    let mut one_larger = rows.clone();
    one_larger.truncate(4);
    assert!(apportion(&one_larger).is_empty());
}

/// On a mesh that trades light between its parts, the deficit takes a fourth factor, the
/// truth without that light over the truth (at scale 1), and size and angles are taken
/// against the truth without it: the four multiply back to model / truth.
#[test]
fn traded_light_is_its_own_factor() {
    let flat = Kind::Flat {
        light: FlatLight::Sun(0.0),
        view: 0.0,
        thickness: 100.0,
    };
    let bunny = |scale: f64| Kind::Scaled {
        scene: "bunny",
        text: super::super::plan::BUNNY,
        lighting: super::super::plan::Lighting::Quad,
        scale,
    };
    let with_direct = |mut r: DeficitRow, d: Rgb| {
        r.direct = Some(mean(d, [0.0; 3]));
        r
    };
    let rows = vec![
        row("incidence", flat, 0.0, [0.9, 0.95, 1.0], [1.0; 3]),
        // Scale 1: the model 0.9 of the truth, the truth without traded light 0.8 of it.
        with_direct(
            row("bunny-quad", bunny(1.0), 1.0, [0.9; 3], [1.0; 3]),
            [0.8, 0.85, 0.9],
        ),
        with_direct(
            row("bunny-quad", bunny(16.0), 16.0, [0.9; 3], [1.0; 3]),
            [0.75; 3],
        ),
        with_direct(
            row("bunny-quad", bunny(64.0), 64.0, [0.9; 3], [1.0; 3]),
            [0.9; 3],
        ),
    ];
    assert!(rows[1].setup.trades_light() && !rows[0].setup.trades_light());
    let a = apportion(&rows);
    assert_eq!(a.len(), 1);
    let a = &a[0];
    assert_eq!(a.interreflection, [0.8, 0.85, 0.9]);
    // Against the truth without traded light: 0.9/0.75 = 1.2 at 16, 1.0 at 64, flat limit
    // 1.0 − 0.2/3.
    let flat = 1.0 - 0.2 / 3.0;
    for c in 0..3 {
        assert!((a.flat[c] - flat).abs() < 1e-12, "{:?}", a.flat);
        let size = 0.9 / [0.8, 0.85, 0.9][c] / flat;
        assert!((a.size[c] - size).abs() < 1e-12, "{:?}", a.size);
        let product = a.size[c] * a.angles[c] * a.profile[c] * a.interreflection[c];
        assert!((product - a.total[c]).abs() < 1e-12, "{c}: {product}");
    }
    // The report names the factor and the CSV carries it (none for the convex row).
    let csv = String::from(deficit_csv(&rows));
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "direct_g").unwrap();
    let cells: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(cells[0][col], "");
    assert_eq!(cells[1][col].parse::<f64>().unwrap(), 0.85);
    let plan = super::plan(true);
    let section = section(&rows, &[], &plan);
    assert!(
        section.summary.contains("interreflection"),
        "{}",
        section.summary
    );
}

/// Every column of `deficit.csv` is documented in `docs/compare.md`.
#[test]
fn every_csv_column_is_documented() {
    let rows = vec![row("incidence", scaled(1.0), 0.0, [1.0; 3], [1.0; 3])];
    let csv = deficit_csv(&rows);
    assert_eq!(crate::output::undocumented(&csv), Vec::<String>::new());
}

/// Every set-up builds its scene (the flat ones from their own text; the mesh ones when the
/// meshes are found), with the model and medium asked for and the objects scaled.
#[test]
fn setups_build_their_scenes() {
    for quick in [true, false] {
        for s in setups(quick) {
            let scene = match s.scene(
                MODEL,
                2,
                16,
                &crate::default_mesh_dirs(&crate::workspace_root()),
            ) {
                Ok(scene) => scene,
                Err(e) if e.kind == SceneErrorKind::MeshNotFound => continue,
                Err(e) => panic!("{}: {e}", s.name()),
            };
            let t = scene
                .materials
                .iter()
                .find_map(|m| match &m.kind {
                    MaterialKind::Translucent(t) => Some(t),
                    _ => None,
                })
                .expect("a translucent material");
            assert_eq!(t.model, MODEL);
            match s.kind {
                // The truth scenes are 1 or fewer units per mm (sphere10 1, bunny 0.2, ...):
                // the units per mm are divided by the scale.
                Kind::Scaled { scale, .. } => {
                    assert!(t.units_per_mm > 0.0 && t.units_per_mm <= 1.0 / scale + 1e-12)
                }
                Kind::Cylinder { radius } => {
                    assert!((t.units_per_mm * radius - 1.0).abs() < 1e-12);
                    assert_eq!((scene.camera.width, scene.camera.height), (16, 16));
                }
                Kind::Flat { .. } => {
                    assert_eq!(t.units_per_mm, 1.0);
                    assert_eq!((scene.camera.width, scene.camera.height), (16, 16));
                }
            }
        }
    }
}

/// The flux ratio of a model that is the truth times a constant is that constant; the
/// head-on row fills the sweep's 0°; a model off at one angle moves it by that angle's weight
/// in the trapezoid rule (by hand: nodes 0°, 45°, 90°, the integrand cos θ sin θ = 1/2 at 45°,
/// 0 at 0° and 90°, so 45° carries all of it).
#[test]
fn the_flux_ratio_weighs_the_exit_angles() {
    let flat = |view| Kind::Flat {
        light: FlatLight::Environment,
        view,
        thickness: 100.0,
    };
    let sweep = [
        row(
            "exit-sun",
            flat(30.0),
            30.0,
            [0.9, 1.8, 0.45],
            [1.0, 2.0, 0.5],
        ),
        row(
            "exit-sun",
            flat(60.0),
            60.0,
            [0.72, 1.8, 0.45],
            [0.8, 2.0, 0.5],
        ),
    ];
    let head_on = row(
        "incidence",
        flat(0.0),
        0.0,
        [1.08, 2.7, 0.54],
        [1.2, 3.0, 0.6],
    );
    let refs: Vec<&DeficitRow> = sweep.iter().collect();
    let f = flux_ratio(&refs, Some(&head_on)).unwrap();
    for (c, v) in f.iter().enumerate() {
        assert!((v - 0.9).abs() < 1e-12, "{c}: {v}");
    }
    let two = [
        row("exit-environment", flat(0.0), 0.0, [5.0; 3], [1.0; 3]),
        row(
            "exit-environment",
            flat(45.0),
            45.0,
            [2.0, 1.0, 0.5],
            [1.0; 3],
        ),
    ];
    let refs: Vec<&DeficitRow> = two.iter().collect();
    let f = flux_ratio(&refs, None).unwrap();
    assert!((f[0] - 2.0).abs() < 1e-12 && (f[1] - 1.0).abs() < 1e-12);
    assert!((f[2] - 0.5).abs() < 1e-12);
    assert!(flux_ratio(&refs[..1], None).is_none());
}
