//! Unit tests of the table's pieces (the integration tests against fresh walks and MCML are
//! under `tests/integration/`).

use super::*;
use crate::catmull_rom::interpolate_catmull_rom;
use crate::quadrature::integrate;
use crate::{Bssrdf, Medium};

/// ∫ x e^{−ax} dx from 0 to x.
fn xexp_integral(a: f64, x: f64) -> f64 {
    (1.0 - (-a * x).exp() * (a * x + 1.0)) / (a * a)
}

/// A smooth test profile T(x) = x e^{−0.7x} + 0.3 x e^{−3x} and its bin integrals.
fn synthetic(x: f64) -> f64 {
    x * (-0.7 * x).exp() + 0.3 * x * (-3.0 * x).exp()
}

fn synthetic_bin(lo: f64, hi: f64) -> f64 {
    let f = |x| xexp_integral(0.7, x) + 0.3 * xexp_integral(3.0, x);
    f(hi) - f(lo)
}

/// ∫ of the spline through `values` over [lo, hi] (exact: Gauss-Legendre per knot piece).
fn spline_integral(knots: &[f64], values: &[f64], lo: f64, hi: f64) -> f64 {
    let mut cuts = vec![lo];
    cuts.extend(knots.iter().copied().filter(|&x| x > lo && x < hi));
    cuts.push(hi);
    cuts.windows(2)
        .map(|w| {
            integrate(
                &|x| interpolate_catmull_rom(knots, values, x).unwrap(),
                w[0],
                w[1],
                4,
            )
        })
        .sum()
}

#[test]
fn grids_are_as_documented() {
    let rho = rho_samples();
    assert_eq!((rho.len(), rho[0], rho[N_RHO - 1]), (N_RHO, 0.0, 1.0));
    let x = radius_knots();
    assert_eq!((x[0], x[1]), (0.0, FIRST_KNOT));
    assert!(x.len() >= 80 && x.len() <= 90, "{}", x.len());
    let last = x[x.len() - 1];
    assert!(last > 900.0 && last <= LAST_KNOT_LIMIT, "{last}");
    for w in x[1..].windows(2) {
        let step = w[1] - w[0];
        // Geometric (20 %) near 0, never more than 0.75 on [4, 16], geometric again
        // beyond.
        assert!(step <= 0.2 * w[0] * (1.0 + 1e-12), "{w:?}");
        if w[0] >= 4.0 && w[0] < LINEAR_END {
            assert!((step - LINEAR_STEP).abs() < 1e-12, "{w:?}");
        }
    }
    let edges = tally_edges(&x);
    assert_eq!(edges.len(), x.len() + 1);
    assert_eq!((edges[1], edges[edges.len() - 1]), (x[1], last));
    for k in 2..x.len() {
        assert!(edges[k] < x[k] && x[k] < edges[k + 1] || k == x.len() - 1);
    }
    // Bands cover every row once; each η has its own streams.
    let p13 = plan(0, 3, 1.0);
    let p10 = plan(0, 0, 1.0);
    let mut covered = vec![0; N_RHO];
    for w in p13.iter().filter(|w| w.min_events == 1) {
        for i in w.rows.clone() {
            covered[i] += 1;
        }
    }
    assert!(covered.iter().all(|&c| c == 1), "{covered:?}");
    assert!(p13.iter().zip(&p10).all(|(a, b)| a.stream != b.stream));
    assert!(
        p13.iter()
            .zip(&p10)
            .all(|(a, b)| a.photons == OTHER_ETA_PHOTON_DIVISOR * b.photons)
    );
    // Every table of every g has its own streams; g ≠ 0 has half the photons.
    let mut streams: Vec<usize> = (0..GS.len())
        .flat_map(|g| (0..ETAS.len()).flat_map(move |e| plan(g, e, 1.0)))
        .map(|w| w.stream)
        .collect();
    let n = streams.len();
    streams.sort_unstable();
    streams.dedup();
    assert_eq!(streams.len(), n);
    for g in 1..GS.len() {
        let pg = plan(g, 3, 1.0);
        assert!(pg.iter().zip(&p13).all(|(a, b)| {
            a.rows == b.rows && ANISOTROPIC_PHOTON_DIVISOR * a.photons == b.photons
        }));
    }
    // ρ' ↦ ρ inverts the similarity relation ρ' = ρ(1 − g)/(1 − ρg).
    for g in [-0.5, 0.0, 0.4, 0.9] {
        for rp in [0.0, 0.1, 0.5, 0.9, 0.999, 1.0] {
            let rho = single_scattering_albedo(rp, g);
            let back = rho * (1.0 - g) / (1.0 - rho * g);
            assert!(
                (back - rp).abs() < 1e-14,
                "g {g} rho' {rp}: {rho} -> {back}"
            );
        }
    }
}

#[test]
fn histopolation_reproduces_bin_integrals_and_point_values() {
    let knots = radius_knots();
    let xs = spline_knots(&knots);
    assert_eq!(xs.len(), knots.len() + 1);
    let edges = tally_edges(&knots);
    let system = Histopolation::new(&knots).unwrap();
    let masses: Vec<f64> = edges
        .windows(2)
        .map(|e| synthetic_bin(e[0], e[1]))
        .collect();
    let v = system.solve(&masses);
    let mut values = vec![0.0];
    values.extend(&v);
    // Every bin integrates to its mass.
    for k in 0..knots.len() {
        let got = spline_integral(&xs, &values, edges[k], edges[k + 1]);
        assert!(
            // (The masses far out are differences of O(1) values: 10⁻¹⁵ absolute.)
            (got - masses[k]).abs() <= 1e-10 * masses[k] + 1e-14,
            "bin {k}: {got} vs {}",
            masses[k]
        );
    }
    // The knot values are the point values of the profile (not its bin averages, which
    // are several % off where the bins are wide), over the accuracy range (up to 16 mean
    // free paths; beyond, the steps grow and this profile's decay of 0.7 per unit makes the
    // spline a few % off between knots).
    let mut worst_avg: f64 = 0.0;
    for j in 1..xs.len() {
        let want = synthetic(xs[j]);
        // (2 % at the extra knot, whose first interval must start at 0.)
        let tol = if j == 1 { 0.02 } else { 0.01 };
        if xs[j] <= 16.0 {
            assert!(
                (values[j] - want).abs() < tol * want,
                "x {}: {} vs {want}",
                xs[j],
                values[j]
            );
        }
        if j >= 2 && xs[j] <= 16.0 {
            let k = j - 1;
            let avg = masses[k] / (edges[k + 1] - edges[k]);
            worst_avg = worst_avg.max((avg / want - 1.0).abs());
        }
    }
    assert!(
        worst_avg > 0.03,
        "bin averages happen to be point values: {worst_avg}"
    );
}

#[test]
fn isotonic_fit_pools_adjacent_violators() {
    assert_eq!(
        non_increasing_fit(&[5.0, 3.0, 4.0, 1.0], &[1.0; 4]),
        vec![5.0, 3.5, 3.5, 1.0]
    );
    assert_eq!(
        non_increasing_fit(&[1.0, 2.0], &[3.0, 1.0]),
        vec![1.25, 1.25]
    );
    // Already ordered: unchanged; a long violation pools across blocks.
    let y = [9.0, 7.0, 7.0, 2.0];
    assert_eq!(non_increasing_fit(&y, &[1.0; 4]), y.to_vec());
    assert_eq!(
        non_increasing_fit(&[3.0, 1.0, 2.0, 6.0], &[1.0; 4]),
        vec![3.0, 3.0, 3.0, 3.0]
    );
}

#[test]
fn unresolved_tail_keeps_its_mass_in_the_fitted_shape() {
    let knots = radius_knots();
    let edges = tally_edges(&knots);
    let exact: Vec<f64> = edges
        .windows(2)
        .map(|e| ((-0.5 * e[0]).exp() - (-0.5 * e[1]).exp()) / 0.5)
        .collect();
    let se: Vec<f64> = exact.iter().map(|m| 0.01 * m).collect();
    // The tally beyond r = 10 is noise: zeros and single hits (relative standard error
    // 1), too few to pool into resolved groups. Their total is kept, spread like the
    // exponential of the resolved bins (κ = 0.5 recovered exactly).
    let mut noisy = exact.clone();
    let mut noisy_se = se.clone();
    let first_bad = edges.partition_point(|&e| e < 10.0);
    for k in first_bad..noisy.len() {
        noisy[k] = if k % 3 == 0 { 5.0 * exact[k] } else { 0.0 };
        noisy_se[k] = noisy[k];
    }
    let (tail, last) = tail_masses(&edges, &noisy, &noisy_se);
    assert_eq!(last, first_bad - 1);
    assert_eq!(tail[..first_bad], exact[..first_bad]);
    let ratio = noisy[first_bad..].iter().sum::<f64>() / exact[first_bad..].iter().sum::<f64>();
    assert!(ratio > 1.0);
    for k in first_bad..exact.len() {
        assert!(
            (tail[k] - ratio * exact[k]).abs() <= 1e-9 * ratio * exact[k] + 1e-300,
            "bin {k}: {} vs {}",
            tail[k],
            ratio * exact[k]
        );
    }
    // A tail that does not decay where it is resolved (here it rises slowly from x = 6 to
    // the last resolved bin) is spread like 1/x² instead.
    let rising: Vec<f64> = edges
        .windows(2)
        .map(|e| {
            let c = 0.5 * (e[0] + e[1]);
            let d = if c < 6.0 {
                (-0.5 * c).exp()
            } else if c < 12.0 {
                (-3.0f64).exp() * (1.0 + 0.01 * (c - 6.0))
            } else {
                (-3.0 - (c - 12.0)).exp()
            };
            d * (e[1] - e[0])
        })
        .collect();
    let rising_se: Vec<f64> = rising
        .iter()
        .zip(&edges)
        .map(|(m, &lo)| if lo < 10.0 { 0.01 * m } else { *m })
        .collect();
    let (spread, last) = tail_masses(&edges, &rising, &rising_se);
    assert_eq!(last, first_bad - 1);
    assert_eq!(spread[..first_bad], rising[..first_bad]);
    let rest: f64 = rising[first_bad..].iter().sum();
    let x0 = edges[first_bad];
    let end = edges[edges.len() - 1];
    for k in first_bad..rising.len() {
        let want = rest * (1.0 / edges[k] - 1.0 / edges[k + 1]) / (1.0 / x0 - 1.0 / end);
        assert!((spread[k] - want).abs() <= 1e-9 * want, "bin {k}");
    }
}

#[test]
fn poorly_resolved_tail_bins_are_pooled_keeping_their_mass() {
    // A power-law tail (as at albedo 1) whose bins beyond x = 20 each have a relative
    // standard error of 30 %, with ±30 % noise: pooled in resolved groups, each group keeps
    // its tallied mass and the density becomes smooth (non-increasing) inside it.
    let knots = radius_knots();
    let edges = tally_edges(&knots);
    let density = |x: f64| 1.0 / (1.0 + x * x);
    let exact: Vec<f64> = edges
        .windows(2)
        .map(|e| (e[1].atan() - e[0].atan()) / 1.0)
        .collect();
    let first_bad = edges.partition_point(|&e| e < 20.0);
    let mut mass = exact.clone();
    let mut se: Vec<f64> = exact.iter().map(|m| 0.01 * m).collect();
    for k in first_bad..mass.len() - 3 {
        mass[k] = exact[k] * if k % 2 == 0 { 1.3 } else { 0.7 };
        se[k] = 0.3 * mass[k];
    }
    let n = mass.len();
    for k in n - 3..n {
        mass[k] = 0.0;
        se[k] = 0.0;
    }
    let (out, last) = tail_masses(&edges, &mass, &se);
    assert_eq!(last, first_bad - 1);
    // Groups are runs of two or three bins (0.3/√2 > 0.2 ≥ 0.3/√3); their sums are kept.
    let mut k = first_bad;
    let mut groups = 0;
    while k + 3 <= n - 3 {
        let kept: f64 = out[k..k + 3].iter().sum();
        let tallied: f64 = mass[k..k + 3].iter().sum();
        assert!((kept - tallied).abs() <= 1e-12 * tallied, "group at {k}");
        groups += 1;
        k += 3;
    }
    assert!(groups >= 3, "{groups}");
    // Within the pooled region the density falls from bin to bin, and stays within 30 %
    // of the exact one (the groups' own noise is ±10 %; the shape extrapolated at the
    // end of the last group adds the rest).
    for k in first_bad..k {
        let d = out[k] / (edges[k + 1] - edges[k]);
        let c = 0.5 * (edges[k] + edges[k + 1]);
        assert!(
            (d / density(c) - 1.0).abs() < 0.3,
            "bin {k}: {d} vs {}",
            density(c)
        );
        if k > first_bad {
            let prev = out[k - 1] / (edges[k] - edges[k - 1]);
            assert!(d <= prev * (1.0 + 1e-12), "bin {k} rises");
        }
    }
    assert!(out.iter().all(|v| v.is_finite() && *v >= 0.0));
}

#[test]
fn table_file_round_trips_and_rejects_damage() {
    let quiet = |_: &str| {};
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| McTableData::generate(2e-5, &quiet).unwrap())
    };
    let data = run(2);
    let bytes = data.to_bytes();
    // The same bytes for any thread count, and a faithful round trip.
    assert_eq!(run(1).to_bytes(), bytes);
    let back = McTableData::from_bytes(&bytes).unwrap();
    assert_eq!(back, data);
    assert_eq!(back.to_bytes(), bytes);
    assert_eq!(data.gs(), GS);
    // Reusing a run's tables gives its bytes; tables whose walks differ (another scale)
    // are run again, as without reuse.
    let reused = McTableData::generate_reusing(2e-5, Some(&data), &quiet).unwrap();
    assert_eq!(reused.to_bytes(), bytes);
    let other_scale = McTableData::generate_reusing(3e-5, Some(&data), &quiet).unwrap();
    assert_eq!(
        other_scale.to_bytes(),
        McTableData::generate(3e-5, &quiet).unwrap().to_bytes()
    );
    assert!(McTableData::from_bytes_v1(&bytes).is_err());
    // Every table's rows hold their own walks: the total (all escaped weight) is at least
    // the binned weight, and the tables differ.
    for t in 0..GS.len() * ETAS.len() {
        for i in 0..N_RHO {
            let binned: f64 = data.mass(t, i).iter().sum();
            let (total, _) = data.total(t, i);
            assert!(
                total >= binned * (1.0 - 1e-6),
                "table {t} row {i}: {total} < {binned}"
            );
        }
    }
    assert!((0..N_RHO).any(|i| data.total(0, i) != data.total(GS.len() * ETAS.len() - 1, i)));
    // Any damage is an error, never a panic.
    for at in [0, 9, 40, bytes.len() / 2, bytes.len() - 1] {
        let mut bad = bytes.clone();
        bad[at] ^= 0x10;
        assert!(McTableData::from_bytes(&bad).is_err(), "flip at {at}");
    }
    for len in [0, 7, 16, 100, bytes.len() - 8, bytes.len() - 1] {
        assert!(
            McTableData::from_bytes(&bytes[..len]).is_err(),
            "length {len}"
        );
    }
    // A well-formed file of other grids is refused.
    let mut other = data.clone();
    other.knots[5] *= 1.0 + 1e-12;
    let err = McTableData::from_bytes(&other.to_bytes()).unwrap_err();
    assert!(err.to_string().contains("grids differ"), "{err}");
    assert!(McTableData::generate(0.0, &quiet).is_err());
}

#[test]
fn embedded_table_is_read() {
    let data = McTableData::embedded().unwrap();
    assert_eq!(data.etas(), ETAS);
    assert_eq!(data.gs(), GS);
    assert_eq!(data.seed(), SEED);
    for g in 0..GS.len() {
        for e in 0..ETAS.len() {
            let t = data.table_index(g, e);
            assert_eq!(data.walks(t), plan(g, e, 1.0).as_slice(), "g {g}, eta {e}");
        }
    }
}

#[test]
fn eta_between_tables_is_linear_and_clamped_outside() {
    let (a, b, mid) = (McTable::new(1.3), McTable::new(1.4), McTable::new(1.35));
    for ((p, q), m) in a
        .profile_values()
        .iter()
        .zip(b.profile_values())
        .zip(mid.profile_values())
    {
        assert!((m - 0.5 * (p + q)).abs() <= 1e-14 * (p + q) + 1e-300);
    }
    assert_eq!(
        McTable::new(2.5).profile_values(),
        McTable::new(1.5).profile_values()
    );
    assert_eq!(
        McTable::new(0.7).profile_values(),
        McTable::new(1.0).profile_values()
    );
    for (eta, inside) in [
        (1.0, true),
        (1.5, true),
        (1.33, true),
        (0.99, false),
        (1.51, false),
    ] {
        assert_eq!(eta_in_range(eta), inside, "{eta}");
    }
    assert!(!eta_in_range(f64::NAN));
    // The uncached build is the cached one.
    assert_eq!(
        McTable::from_embedded_uncached(1.35).profile_values(),
        mid.profile_values()
    );
}

#[test]
fn anisotropic_media_read_the_tables_of_their_g_at_their_reduced_coefficients() {
    // g = 0.5 lies a third of the way from the 0.4 table to the 0.7 one.
    let (lo, hi, mid) = (
        McTable::anisotropic(1.3, 0.4),
        McTable::anisotropic(1.3, 0.7),
        McTable::anisotropic(1.3, 0.5),
    );
    assert_eq!(mid.g(), 0.5);
    let mut differ = 0;
    for ((p, q), m) in lo
        .profile_values()
        .iter()
        .zip(hi.profile_values())
        .zip(mid.profile_values())
    {
        let want = (2.0 * p + q) / 3.0;
        assert!((m - want).abs() <= 1e-13 * (p + q) + 1e-300);
        differ += usize::from(p != q);
    }
    assert!(differ > N_RHO, "the tables of g = 0.4 and 0.7 differ");
    assert_ne!(
        McTable::anisotropic(1.3, 0.4).profile_values(),
        McTable::new(1.3).profile_values()
    );
    // Outside [0, 0.9]: the end table at the reduced coefficients. σ_s = 2, g = −1/2 has
    // σ'_s = 3, the same model as σ_s = 3, g = 0; σ_s = 20, g = 0.95 has σ'_s = 1, as
    // σ_s = 10, g = 0.9.
    for ((sa, ga), (sb, gb)) in [((2.0, -0.5), (3.0, 0.0)), ((20.0, 0.95), (10.0, 0.9))] {
        let a = Medium::new([0.1, 0.3, 0.0], [sa, 2.0 * sa, 3.0 * sa], ga, 1.3).unwrap();
        let b = Medium::new([0.1, 0.3, 0.0], [sb, 2.0 * sb, 3.0 * sb], gb, 1.3).unwrap();
        let (ma, mb) = (McTableModel::new(a), McTableModel::new(b));
        assert!(!ma.g_in_range() && mb.g_in_range());
        for ch in 0..3 {
            let (x, y) = (ma.reduced_albedo(ch), mb.reduced_albedo(ch));
            assert!((x - y).abs() < 1e-15, "{x} vs {y}");
            for r in [0.0, 0.01, 0.3, 2.0, 40.0] {
                let (x, y) = (ma.rd(ch, r), mb.rd(ch, r));
                assert!(
                    (x - y).abs() <= 1e-12 * y,
                    "g {ga} ch {ch} r {r}: {x} vs {y}"
                );
            }
        }
    }
    assert!(g_in_range(0.0) && g_in_range(0.9) && g_in_range(0.55));
    assert!(!g_in_range(-0.01) && !g_in_range(0.91) && !g_in_range(f64::NAN));
    let a = Medium::new([0.1; 3], [1.0; 3], 0.5, 1.3).unwrap();
    assert!(McTableModel::new(a).eta_in_range());
    let out = Medium::new([0.1; 3], [1.0; 3], 0.0, 1.7).unwrap();
    assert!(!McTableModel::new(out).eta_in_range());
}
