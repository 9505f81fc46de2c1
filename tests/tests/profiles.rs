//! Cross-crate tests: the models of `sss-bssrdf` through the profile and plot code of
//! `sss-render`.

use sss_bssrdf::MediumSpec;
use sss_bssrdf::monte_carlo::{self, BinSpacing, WalkConfig};
use sss_bssrdf::presets::PRESETS;
use sss_bssrdf::profile_rows::{ProfileModel, ProfileRequest, compute};
use sss_bssrdf::{Medium, ModelKind};
use std::path::PathBuf;

/// The analytic models (every profile model but the Monte Carlo walk), in `ModelKind` order.
fn models() -> impl Iterator<Item = ProfileModel> {
    ProfileModel::ALL
        .into_iter()
        .filter(|m| *m != ProfileModel::MonteCarlo)
}

fn request(model: ProfileModel, preset: &str, r_max: f64, steps: usize) -> ProfileRequest {
    ProfileRequest {
        steps,
        ..ProfileRequest::new(model, MediumSpec::Preset(preset.into()), r_max)
    }
}

#[test]
fn every_model_gives_finite_profiles_for_every_preset() {
    for model in models() {
        for preset in &PRESETS {
            for log in [false, true] {
                let req = ProfileRequest {
                    log,
                    ..request(model, preset.name, 50.0, 64)
                };
                let t = compute(&req, &|_| {}).unwrap();
                assert_eq!(t.rows.len(), 64);
                for ch in 0..3 {
                    let total = t.total[ch];
                    assert!(
                        total.is_finite() && (0.0..=1.0).contains(&total),
                        "{model:?} {} total {total}",
                        preset.name
                    );
                }
                for row in &t.rows {
                    assert!(row.r > 0.0 && row.r <= 50.0);
                    for v in row.rd {
                        assert!(
                            v.is_finite() && v >= 0.0,
                            "{model:?} {} r {}: {v}",
                            preset.name,
                            row.r
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn profile_model_names_are_the_library_names() {
    assert_eq!(models().count(), ModelKind::ALL.len());
    for (m, k) in models().zip(ModelKind::ALL) {
        assert_eq!(m.kind(), Some(k));
        assert_eq!(m.name().parse::<ModelKind>().unwrap(), k);
    }
}

#[test]
fn monte_carlo_table_is_the_library_simulation() {
    let req = ProfileRequest {
        photons: 3000,
        seed: 11,
        ..request(ProfileModel::MonteCarlo, "skin2", 6.0, 12)
    };
    let t = compute(&req, &|_| {}).unwrap();
    let direct = monte_carlo::simulate(
        &Medium::preset("skin2").unwrap(),
        &WalkConfig {
            photons: 3000,
            seed: 11,
            r_max: 6.0,
            bins: 12,
            channels: [true; 3],
            spacing: BinSpacing::Linear,
        },
    )
    .unwrap();
    assert_eq!(t.total, direct.total);
    for (i, row) in t.rows.iter().enumerate() {
        for ch in 0..3 {
            assert_eq!(row.rd[ch], direct.rd[ch][i]);
            assert_eq!(row.se.unwrap()[ch], direct.se[ch][i]);
        }
    }
}

#[test]
fn every_model_plots() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("profiles-plot");
    std::fs::create_dir_all(&dir).unwrap();
    for model in models() {
        let t = compute(&request(model, "potato", 20.0, 50), &|_| {}).unwrap();
        let path = dir.join(format!("{}.svg", model.name()));
        sss_cli::commands::profile::plot(&t, &path, false).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains("<svg") && text.contains("green"));
    }
}

#[test]
fn mc_table_refuses_an_eta_outside_its_tables() {
    // The tables cover η from 1 to 1.5; outside, `sss profile` refuses rather than clamp.
    for (eta, ok) in [
        (0.9, false),
        (1.0, true),
        (1.45, true),
        (1.5, true),
        (1.6, false),
    ] {
        let req = ProfileRequest {
            eta: Some(eta),
            ..request(ProfileModel::McTable, "skin1", 4.0, 8)
        };
        match compute(&req, &|_| {}) {
            Ok(t) => assert!(ok && t.total[0] > 0.0, "eta {eta}"),
            Err(e) => {
                assert!(!ok, "eta {eta}: {e}");
                let msg = e.to_string();
                assert!(msg.contains("mc-table") && msg.contains("--eta"), "{msg}");
            }
        }
    }
}
