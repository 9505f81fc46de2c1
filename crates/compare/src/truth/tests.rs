use super::plan::Lighting;
use super::*;

fn truth_of(image: Vec<Rgb>, se: Vec<Rgb>) -> Truth {
    let n = image.len();
    Truth {
        width: n as u32,
        height: 1,
        translucent: (0..n).collect(),
        pixels: (0..n).collect(),
        image,
        se,
        spp: 4,
        seconds: 1.5,
    }
}

/// The reference's noise adds σ² to every squared difference: removed, the relative RMSE of a
/// perfect image against a noisy reference is 0, and an image off by 10 % everywhere scores
/// 10 % whatever the reference's noise.
#[test]
fn the_references_noise_is_removed_from_the_score() {
    let n = 20_000;
    // A reference of mean 1 whose pixels are off by ±σ (σ = 0.2), alternately: its squared
    // differences from the true 1 average exactly σ².
    let sigma = 0.2;
    let image: Vec<Rgb> = (0..n)
        .map(|i| [1.0 + if i % 2 == 0 { sigma } else { -sigma }; 3])
        .collect();
    let truth = truth_of(image, vec![[sigma; 3]; n]);
    let perfect = vec![[1.0; 3]; n];
    let s = score(&perfect, &truth);
    assert!(s.rel_rmse < 1e-6, "{}", s.rel_rmse);
    assert!(s.mean_ratio.iter().all(|r| (r - 1.0).abs() < 1e-12));
    let off = vec![[1.1; 3]; n];
    let s = score(&off, &truth);
    assert!((s.rel_rmse - 0.1).abs() < 1e-3, "{}", s.rel_rmse);
    assert!(s.mean_ratio.iter().all(|r| (r - 1.1).abs() < 1e-12));
    // The noise figure: RMS σ over the mean.
    assert!((truth.noise() - sigma).abs() < 1e-12);
}

/// The fit recovers error = a/√(t − t₀) from exact points, ignores runs under 4 paths, and
/// inverts to the time of a given error.
#[test]
fn the_crossover_fits_one_over_the_square_root_of_time() {
    let (a, t0) = (0.3, 0.5);
    let runs: Vec<(u32, f64, f64, f64)> = [1u32, 4, 16, 64]
        .iter()
        .map(|&spp| {
            let shading = 0.01 * spp as f64;
            // The 1-path run is off the curve: it must not count.
            let e = if spp == 1 { 10.0 } else { a / shading.sqrt() };
            (spp, t0 + shading, shading, e)
        })
        .collect();
    let x = Crossover::fit(&runs).unwrap();
    assert!(
        (x.a - a).abs() < 1e-12 && (x.overhead - t0).abs() < 1e-12,
        "{x:?}"
    );
    assert!((x.seconds_for(0.3).unwrap() - (t0 + 1.0)).abs() < 1e-12);
    assert_eq!(x.seconds_for(0.0), None);
    assert_eq!(Crossover::fit(&runs[..1]), None);
}

#[test]
fn a_cached_reference_round_trips_and_damage_is_named() {
    let mut t = truth_of(vec![[1.0, 2.0, 3.0], [0.5, 0.25, 0.125]], vec![[0.1; 3]; 2]);
    t.translucent = vec![1];
    // A 2 × 1 image has no interior pixel.
    t.pixels = Vec::new();
    let bytes = volpath_reference::encode(&t);
    assert_eq!(volpath_reference::decode(&bytes).unwrap(), t);
    let cut = &bytes[..bytes.len() - 1];
    assert!(
        volpath_reference::decode(cut)
            .unwrap_err()
            .contains("bytes after the header")
    );
    let mut bad = bytes.clone();
    let at = bad.len() - 4;
    bad[at] = 7;
    assert!(
        volpath_reference::decode(&bad)
            .unwrap_err()
            .contains("out of range")
    );
}

/// Interior pixels: a 5 × 4 image whose translucent pixels are its 4 × 3 top-left block has
/// the two pixels at (1, 1) and (2, 1) inside; a hole takes out its neighbours.
#[test]
fn the_scored_pixels_are_those_inside_the_silhouette() {
    let block: Vec<usize> = (0..20).filter(|i| i % 5 < 4 && i / 5 < 3).collect();
    assert_eq!(volpath_reference::interior(&block, 5, 4), vec![6, 7]);
    let full: Vec<usize> = (0..20).collect();
    assert_eq!(
        volpath_reference::interior(&full, 5, 4),
        vec![6, 7, 8, 11, 12, 13]
    );
    let holed: Vec<usize> = full.iter().copied().filter(|&i| i != 12).collect();
    assert_eq!(
        volpath_reference::interior(&holed, 5, 4),
        Vec::<usize>::new()
    );
}

#[test]
fn every_csv_column_is_documented() {
    let csv = truth_csv(&[]);
    assert_eq!(
        super::super::output::undocumented(&csv),
        Vec::<String>::new()
    );
}

/// Each case's scene loads (meshes aside), carries the case's medium in every translucent
/// material with the asked model, and the environment case has the one uniform light.
#[test]
fn cases_build_their_scenes() {
    for quick in [true, false] {
        let p = plan(quick);
        assert!(!p.cases.is_empty());
        for case in p.cases.iter().filter(|c| c.scene.starts_with("sphere")) {
            let s = case.scene(ModelKind::Burley, p.shrink, &[]).unwrap();
            assert_eq!(s.name, case.name());
            let want = (case.medium.make)();
            for m in &s.materials {
                if let MaterialKind::Translucent(t) = &m.kind {
                    assert_eq!(t.medium, want);
                    assert_eq!(t.model, ModelKind::Burley);
                }
            }
            match case.lighting {
                Lighting::Environment => {
                    assert_eq!(s.lights, vec![Light::Environment { radiance: [1.0; 3] }])
                }
                Lighting::Quad => assert!(matches!(s.lights[..], [Light::Quad { .. }])),
            }
        }
    }
    // Every medium of the full plan: the absorbing one below albedo 0.5 in every channel.
    let absorbing = (plan::ABSORBING.make)();
    assert!((0..3).all(|c| absorbing.albedo(c) < 0.5));
}
