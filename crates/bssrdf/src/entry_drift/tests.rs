use super::*;
use crate::quadrature::integrate;
use std::f64::consts::PI;

/// The sums of `photons` walks of channel 0 from outside cosine `cos_i`, in chunks seeded
/// 1000, 1001, …, tallied in channel 0's bins; `single`: one collision only.
fn sums(medium: &Medium, radius: Option<f64>, cos_i: f64, photons: u64, single: bool) -> Sums {
    sums_seeded(medium, radius, cos_i, photons, single, 1000)
}

/// [`sums`] with chunks seeded `seed`, `seed` + 1, ….
fn sums_seeded(
    medium: &Medium,
    radius: Option<f64>,
    cos_i: f64,
    photons: u64,
    single: bool,
    seed: u64,
) -> Sums {
    let e = edges(medium, 0, radius);
    let start = refracted(cos_i, medium.eta()).unwrap();
    let chunks = photons.div_ceil(CHUNK_PHOTONS);
    let parts: Vec<Sums> = (0..chunks)
        .into_par_iter()
        .map(|k| {
            let n = CHUNK_PHOTONS.min(photons - k * CHUNK_PHOTONS);
            run_chunk(medium, 0, radius, start, &e, n, seed + k, single)
        })
        .collect();
    let mut total = Sums::new();
    for p in &parts {
        total.add(p);
    }
    total
}

/// Single scattering of a beam entering an index-matched half-space (σ_t = 1/mm, isotropic
/// phase function) at 60°, written from the geometry alone: a collision at depth-distance s
/// along the beam, c = s·d₀, scatters isotropically, and the light reaching the surface point
/// y has density σ_s e^{−σ_t s} · e^{−σ_t L} |c_z| / (4π L³) per unit area (L = |y − c|; the
/// solid angle dω = cos θ dA / L²). Per chord bin, k = 2 ∫ρ cos φ dA / ∫ρ dA by quadrature
/// (Gauss–Legendre in r and in u = 1 − e^{−σ_t s}, the trapezoid rule in φ, exact for a
/// periodic integrand to the rule's order) against the walk's one-collision tally, within
/// 5 standard errors plus 0.01, in every bin holding 2 % or more of a bin's share of the light.
#[test]
fn single_scattering_drift_matches_quadrature() {
    let (sigma_s, sigma_a) = (0.5, 0.5);
    let medium = Medium::new([sigma_a; 3], [sigma_s; 3], 0.0, 1.0).unwrap();
    let cos_i: f64 = 0.5;
    let sin_i = (1.0 - cos_i * cos_i).sqrt();
    let photons = 1 << 19;
    let s = sums(&medium, None, cos_i, photons, true);
    let (k_walk, se) = raw_k(&s, photons);
    let e = edges(&medium, 0, None);
    let density = |r: f64, phi: f64| {
        let y = DVec3::new(r * phi.cos(), r * phi.sin(), 0.0);
        integrate(
            &|u: f64| {
                let depth = -(1.0 - u).ln();
                let c = DVec3::new(sin_i, 0.0, -cos_i) * depth;
                let l = (y - c).length();
                sigma_s * (-l).exp() * c.z.abs() / (4.0 * PI * l * l * l)
            },
            0.0,
            1.0,
            64,
        )
    };
    let phis = 64;
    // ∫ r dr ∫ dφ ρ(r, φ) cos^p φ over bin b (p = 0, 1).
    let moment = |b: usize, p: i32| {
        integrate(
            &|r: f64| {
                (0..phis)
                    .map(|j| {
                        let phi = 2.0 * PI * j as f64 / phis as f64;
                        density(r, phi) * phi.cos().powi(p)
                    })
                    .sum::<f64>()
                    * r
            },
            e[b],
            e[b + 1],
            16,
        )
    };
    let total_w: f64 = s.w.iter().sum();
    let mut checked = 0;
    for b in 1..BINS {
        if s.w[b] < 0.02 * total_w / BINS as f64 {
            continue;
        }
        let (m0, m1) = (moment(b, 0), moment(b, 1));
        let k_quad = 2.0 * m1 / m0;
        let tol = 5.0 * se[b] + 0.01;
        eprintln!(
            "bin {b}: walk {:.4} ± {:.4}, quadrature {k_quad:.4}",
            k_walk[b], se[b]
        );
        assert!(
            (k_walk[b] - k_quad).abs() < tol,
            "bin {b} ({:.3}–{:.3} mm): walk {:.4} ± {:.4}, quadrature {k_quad:.4}",
            e[b],
            e[b + 1],
            k_walk[b],
            se[b]
        );
        checked += 1;
    }
    assert!(checked >= 12, "only {checked} bins checked");
}

/// A beam at normal incidence has no direction along the surface: by symmetry its exit
/// density is the same at φ and −φ and at φ and π − φ, so k is 0 in every bin within 5
/// standard errors (a walk that tallied the wrong azimuth, or lost the beam's symmetry, shows).
#[test]
fn normal_incidence_does_not_drift() {
    let medium = Medium::preset("skin1").unwrap();
    let photons = 1 << 16;
    for radius in [None, Some(5.0)] {
        let s = sums(&medium, radius, 1.0, photons, false);
        let (k, se) = raw_k(&s, photons);
        for b in 0..BINS {
            assert!(
                k[b].abs() <= 5.0 * se[b] + 1e-12,
                "{radius:?}, bin {b}: k {:.4} ± {:.4}",
                k[b],
                se[b]
            );
        }
    }
}

/// A ball a thousand times wider than the light travels is the half-space: k within 0.03 at
/// every radius and incidence tested (the walks share their random numbers chunk for chunk).
#[test]
fn a_huge_ball_drifts_as_the_half_space() {
    let medium = Medium::preset("skin1").unwrap();
    let flat = EntryDrift::with_photons(&medium, None, 1 << 14).unwrap();
    let ball = EntryDrift::with_photons(&medium, Some(5000.0), 1 << 14).unwrap();
    assert_eq!(ball.radius(), Some(5000.0));
    assert_eq!(flat.radius(), None);
    for ch in 0..3 {
        let mfp = medium.reduced_mean_free_path(ch);
        for r in [0.3 * mfp, mfp, 3.0 * mfp] {
            for cos_i in [0.1, 0.5, 0.9] {
                let (a, b) = (flat.k(ch, r, cos_i), ball.k(ch, r, cos_i));
                assert!(
                    (a - b).abs() < 0.03,
                    "channel {ch}, r {r:.3}, cos {cos_i}: half-space {a:.4}, ball {b:.4}"
                );
            }
        }
    }
}

/// Oblique light leaves ahead of where it entered, more so the more grazing it enters and the
/// nearer the entry point (a shifted diffusion source: k ≈ Δ·|d ln R_d/dr|, larger where the
/// profile falls faster), in every channel of skin1 and in its ball.
#[test]
fn oblique_light_drifts_forward() {
    let medium = Medium::preset("skin1").unwrap();
    for radius in [None, Some(10.0)] {
        let d = EntryDrift::with_photons(&medium, radius, 1 << 15).unwrap();
        for ch in 0..3 {
            let mfp = medium.reduced_mean_free_path(ch);
            let grazing = d.k(ch, mfp, 0.2);
            let steep = d.k(ch, mfp, 0.8);
            let far = d.k(ch, 4.0 * mfp, 0.2);
            assert!(
                grazing > steep && steep > 0.1 && grazing > far && far > 0.1,
                "{radius:?}, channel {ch}: k at 1 mfp {grazing:.3} (78°), {steep:.3} (37°); at \
                 4 mfp {far:.3}"
            );
            assert_eq!(d.k(ch, mfp, 1.0), 0.0, "normal incidence");
        }
    }
}

/// The factor S is multiplied by: 1 at normal incidence and exit, never negative, symmetric in
/// entry and exit (reciprocity), and 1 on average over either azimuth (it moves light, it
/// neither adds nor removes any), for every radius and angle on a grid.
#[test]
fn the_factor_moves_light_and_is_reciprocal() {
    let medium = Medium::preset("ketchup").unwrap();
    let d = EntryDrift::with_photons(&medium, Some(3.0), 1 << 13).unwrap();
    assert_eq!(d.factor(0.5, 1.0, 0.7, 1.0, -0.3), [1.0; 3]);
    let n = 48;
    for r in [0.0, 0.05, 0.3, 1.0, 5.0, 50.0] {
        for cos_i in [0.0, 0.05, 0.3, 0.7, 1.0] {
            for cos_o in [0.0, 0.2, 0.9] {
                for j in 0..n {
                    let pi = (2.0 * PI * j as f64 / n as f64).cos();
                    for po in [-1.0, -0.4, 0.0, 0.6, 1.0] {
                        let f = d.factor(r, cos_i, pi, cos_o, po);
                        let g = d.factor(r, cos_o, po, cos_i, pi);
                        assert_eq!(f, g, "reciprocity at r {r}, {cos_i}/{pi}, {cos_o}/{po}");
                        assert!(f.iter().all(|x| *x >= 0.0 && x.is_finite()), "{f:?}");
                    }
                }
                for po in [-1.0, 0.5] {
                    let mut mean = [0.0; 3];
                    for j in 0..n {
                        let pi = (2.0 * PI * (j as f64 + 0.5) / n as f64).cos();
                        let f = d.factor(r, cos_i, pi, cos_o, po);
                        for c in 0..3 {
                            mean[c] += f[c] / n as f64;
                        }
                    }
                    // Over φ_i the exit's term stays: its own mean over φ_o is 0.
                    let exit: Rgb = std::array::from_fn(|c| {
                        let (ki, ko) = (d.k(c, r, cos_i), d.k(c, r, cos_o));
                        1.0 + ko * po / (ki.abs() + ko.abs()).max(1.0)
                    });
                    for c in 0..3 {
                        assert!(
                            (mean[c] - exit[c]).abs() < 1e-12,
                            "r {r}, cos {cos_i}/{cos_o}: mean over φ_i {:.6}, expected {:.6}",
                            mean[c],
                            exit[c]
                        );
                    }
                }
            }
        }
    }
    // Nonsense in, 1 ± k out (never NaN).
    let f = d.factor(f64::NAN, f64::NAN, f64::NAN, f64::INFINITY, 2.0);
    assert!(f.iter().all(|x| x.is_finite() && *x >= 0.0), "{f:?}");
}

/// The walks are the same for any number of threads (chunks seeded by their index, summed in
/// order), and a ball's radius that is not finite and positive is refused.
#[test]
fn thread_count_does_not_matter_and_bad_radii_are_refused() {
    let medium = Medium::preset("skin1").unwrap();
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| EntryDrift::with_photons(&medium, Some(4.0), 3 * CHUNK_PHOTONS).unwrap())
    };
    let (a, b) = (run(1), run(3));
    for ch in 0..3 {
        for &r in a.centres(ch) {
            for cos_i in COS_NODES {
                assert_eq!(a.k(ch, r, cos_i).to_bits(), b.k(ch, r, cos_i).to_bits());
            }
        }
    }
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let e = EntryDrift::new(&medium, Some(bad)).unwrap_err().to_string();
        assert!(e.contains("radius"), "{e}");
    }
}

/// The chord bins, by hand: skin1's red (reduced mean free path 1/(0.032 + 0.74) mm, diffusion
/// length 1/√(3 σ_a σ'_t)) from a twentieth of the mean free path to 16 diffusion lengths in
/// the half-space, to a ball's diameter where that is shorter, with the first edge at most a
/// hundredth of the last; a medium without absorption (no diffusion length) reaches 1 000 mean
/// free paths; the bins' widths grow by one ratio.
#[test]
fn the_bins_reach_sixteen_diffusion_lengths_or_the_diameter() {
    let skin1 = Medium::preset("skin1").unwrap();
    let (sa, ss) = (skin1.sigma_a()[0], skin1.sigma_s()[0]);
    let mfp = 1.0 / (sa + ss);
    let reach = 16.0 / (3.0 * sa * (sa + ss)).sqrt();
    let check = |e: &[f64], first: f64, last: f64| {
        assert_eq!(e.len(), BINS + 1);
        assert_eq!(e[0], 0.0);
        assert!(
            (e[1] / first - 1.0).abs() < 1e-12,
            "first edge {} vs {first}",
            e[1]
        );
        assert!(
            (e[BINS] / last - 1.0).abs() < 1e-12,
            "last edge {} vs {last}",
            e[BINS]
        );
        let ratio = e[2] / e[1];
        for b in 2..BINS {
            assert!((e[b + 1] / e[b] / ratio - 1.0).abs() < 1e-9, "bin {b}");
        }
    };
    check(&edges(&skin1, 0, None), 0.05 * mfp, reach);
    check(&edges(&skin1, 0, Some(100.0)), 0.05 * mfp, reach);
    check(&edges(&skin1, 0, Some(5.0)), 0.05 * mfp, 10.0);
    check(&edges(&skin1, 0, Some(0.5)), 0.01, 1.0);
    let lossless = Medium::new([0.0; 3], [2.0; 3], 0.0, 1.3).unwrap();
    check(&edges(&lossless, 0, None), 0.05 * 0.5, 500.0);
}

/// Light refracted from outside cosine μ through η leaves along +x with sin θ_t = sin θ_i / η
/// (Snell), straight down at normal incidence; into a medium less dense than outside (η < 1)
/// none enters beyond the critical angle, so a walk there drifts nothing, and finishes (a beam
/// along the surface of a ball would glance off it for ever).
#[test]
fn the_beam_enters_refracted() {
    for (cos_i, eta) in [(1.0, 1.3), (0.5, 1.3), (0.05, 1.5), (0.3, 1.0), (0.9, 0.8)] {
        let d = refracted(cos_i, eta).unwrap();
        let sin_i = (1.0f64 - cos_i * cos_i).sqrt();
        assert!((d.x - sin_i / eta).abs() < 1e-12, "{d:?}");
        assert_eq!(d.y, 0.0);
        assert!((d.length() - 1.0).abs() < 1e-12 && d.z < 0.0, "{d:?}");
    }
    assert_eq!(refracted(0.5, 0.8), None);
    assert_eq!(refracted(0.0, 1.0), None);
    let light = Medium::new([0.1; 3], [1.0; 3], 0.0, 0.8).unwrap();
    let d = EntryDrift::with_photons(&light, Some(3.0), 1 << 12).unwrap();
    // cos θ_i = 0.5: sin θ_i / η = 1.08, beyond the critical angle.
    assert_eq!(d.k(0, 0.5, 0.5), 0.0);
    assert!(d.k(0, 0.5, 0.8) > 0.0);
}

/// The standard errors are honest: over 12 independent runs, k's spread in each bin holding
/// light is its reported standard error on average (the ratio within 0.75–1.33, averaged
/// over the bins), so the shrinking towards 0 and the tests' tolerances rest on a true noise.
#[test]
fn standard_errors_match_the_spread_of_independent_runs() {
    let medium = Medium::preset("skin1").unwrap();
    let photons = 1 << 13;
    let runs: Vec<(Vec<f64>, Vec<f64>)> = (0..12)
        .map(|i| {
            raw_k(
                &sums_seeded(&medium, None, 0.5, photons, false, 1 << (20 + i)),
                photons,
            )
        })
        .collect();
    let mut ratios = Vec::new();
    for b in 0..BINS {
        let ks: Vec<f64> = runs.iter().map(|r| r.0[b]).collect();
        let se: f64 = runs.iter().map(|r| r.1[b]).sum::<f64>() / runs.len() as f64;
        if se <= 0.0 || se > 0.3 || ks.contains(&0.0) {
            continue;
        }
        let mean = ks.iter().sum::<f64>() / ks.len() as f64;
        let var = ks.iter().map(|k| (k - mean).powi(2)).sum::<f64>() / (ks.len() - 1) as f64;
        ratios.push(var.sqrt() / se);
    }
    assert!(ratios.len() >= 10, "{} bins", ratios.len());
    let mean = ratios.iter().sum::<f64>() / ratios.len() as f64;
    assert!(
        (0.75..1.33).contains(&mean),
        "spread / standard error {mean:.3} ({ratios:?})"
    );
}

/// The shrinking by hand: k(1 − s²/k²) where |k| > s, else 0; clamped to [−1, 1]; 0 for
/// what is not a number.
#[test]
fn shrink_by_hand() {
    assert!((shrink(0.5, 0.1) - 0.48).abs() < 1e-15);
    assert!((shrink(-0.5, 0.1) + 0.48).abs() < 1e-15);
    assert!((shrink(0.3, 0.2) - 0.3 * (1.0 - 0.04 / 0.09)).abs() < 1e-15);
    assert_eq!(shrink(0.05, 0.1), 0.0);
    assert_eq!(shrink(0.1, 0.1), 0.0);
    assert_eq!(shrink(3.0, 0.1), 1.0);
    assert_eq!(shrink(-3.0, 0.1), -1.0);
    assert_eq!(shrink(0.4, 0.0), 0.4);
    assert_eq!(shrink(f64::NAN, 0.1), 0.0);
}

/// Between incidence nodes k is linear in cos θ_i (the mean of two neighbouring nodes' values
/// half-way between them), below the first node it is the first node's, and from the last
/// node it falls linearly to 0 at normal incidence; the accessors give the bins' centres and
/// a positive standard error where light arrived.
#[test]
fn k_between_nodes_and_the_accessors() {
    let medium = Medium::preset("skin1").unwrap();
    let d = EntryDrift::with_photons(&medium, Some(6.0), 1 << 13).unwrap();
    let last = COS_NODES.len() - 1;
    for ch in 0..3 {
        for r in [0.2, 1.0, 4.0] {
            let at = d.at(r);
            for j in 0..last {
                let (a, b) = (at.ks(COS_NODES[j])[ch], at.ks(COS_NODES[j + 1])[ch]);
                let mid = at.ks(0.5 * (COS_NODES[j] + COS_NODES[j + 1]))[ch];
                assert!((mid - 0.5 * (a + b)).abs() < 1e-12, "{ch} {r} node {j}");
            }
            assert_eq!(at.ks(0.0)[ch], at.ks(COS_NODES[0])[ch]);
            let top = at.ks(COS_NODES[last])[ch];
            let half = at.ks(0.5 * (1.0 + COS_NODES[last]))[ch];
            assert!((half - 0.5 * top).abs() < 1e-12);
            assert_eq!(d.k(ch, r, 0.3), at.ks(0.3)[ch]);
        }
        let e = edges(&medium, ch, Some(6.0));
        let c = d.centres(ch);
        assert_eq!(c.len(), BINS);
        for b in 0..BINS {
            assert!((c[b] - 0.5 * (e[b] + e[b + 1])).abs() < 1e-12 * e[BINS]);
        }
        // Light reaches the first bins at every node: their errors are positive and small.
        for j in 0..COS_NODES.len() {
            let se = d.k_se(ch, j, 2);
            assert!(se > 0.0 && se < 0.5, "channel {ch}, node {j}: {se}");
        }
    }
}

/// A medium that absorbs far more than it scatters has a diffusion length under ten mean free
/// paths: its bins still reach ten mean free paths.
#[test]
fn strong_absorbers_reach_ten_mean_free_paths() {
    let m = Medium::new([10.0; 3], [0.1; 3], 0.0, 1.3).unwrap();
    let mfp = 1.0 / 10.1;
    assert!(16.0 / m.sigma_tr(0) < 10.0 * mfp);
    let e = edges(&m, 0, None);
    assert!((e[BINS] / (10.0 * mfp) - 1.0).abs() < 1e-12, "{}", e[BINS]);
}
