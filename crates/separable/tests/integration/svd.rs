//! SVD low-rank kernels (Jimenez et al. 2015, §3): exact reconstruction at full rank and the
//! Eckart–Young error of every truncation.

use crate::common;

use sss_separable::{TapPlacement, svd};

#[test]
fn full_rank_svd_reconstructs_the_kernel_to_rounding() {
    let m = common::model("skin1");
    let k = common::kernel2d(m.as_ref(), 63);
    let s = svd::decompose(&k).unwrap();
    let n = k.cells;
    for c in 0..3 {
        let full = s.reconstruct(c, n);
        let peak = k.mass[c].iter().fold(0.0f64, |a, b| a.max(*b));
        let worst = full
            .iter()
            .zip(&k.mass[c])
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(
            worst <= 1e-13 * peak,
            "channel {c}: {worst:e} vs peak {peak:e}"
        );
        // Singular values are sorted, non-negative and finite.
        let sp = s.spectrum(c);
        assert!(sp.windows(2).all(|w| w[0] >= w[1]) && sp[n - 1] >= 0.0);
    }
}

#[test]
fn rank_k_error_is_the_root_sum_of_discarded_squared_singular_values() {
    let m = common::model("skin1");
    let k = common::kernel2d(m.as_ref(), 63);
    let s = svd::decompose(&k).unwrap();
    for c in 0..3 {
        let sp = s.spectrum(c);
        for rank in 1..=6 {
            // ‖K − K_k‖_F measured directly on the matrices …
            let approx = s.reconstruct(c, rank);
            let measured = approx
                .iter()
                .zip(&k.mass[c])
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                .sqrt();
            // … against √(Σ_{i ≥ k} sᵢ²) from the spectrum.
            let predicted = sp[rank..].iter().map(|x| x * x).sum::<f64>().sqrt();
            assert!(
                (measured - predicted).abs() <= 1e-9 * predicted + 1e-14 * sp[0],
                "channel {c} rank {rank}: measured {measured:e}, predicted {predicted:e}"
            );
            assert_eq!(s.frobenius_error(c, rank), predicted);
        }
        // The error falls with the rank (Figure 4): every rank adds a non-zero component.
        assert!((1..6).all(|r| s.frobenius_error(c, r + 1) < s.frobenius_error(c, r)));
    }
}

#[test]
fn separable_rank_k_kernel_is_the_truncation_renormalised() {
    let m = common::model("marble");
    let k = common::kernel2d(m.as_ref(), 31);
    let s = svd::decompose(&k).unwrap();
    let n = k.cells;
    for rank in 1..=6 {
        let sep = s.separable(rank, TapPlacement::Grid).unwrap();
        assert_eq!(sep.terms.len(), rank);
        for c in 0..3 {
            let trunc = s.reconstruct(c, rank);
            let scale = k.total[c] / trunc.iter().sum::<f64>();
            for iy in 0..n {
                for ix in 0..n {
                    let w: f64 = sep
                        .terms
                        .iter()
                        .map(|t| t.horizontal.taps[ix].weight[c] * t.vertical.taps[iy].weight[c])
                        .sum();
                    let want = scale * trunc[iy * n + ix];
                    assert!(
                        (w - want).abs() <= 1e-12 * k.total[c],
                        "rank {rank} ch {c} ({ix},{iy}): {w:e} vs {want:e}"
                    );
                }
            }
        }
    }
}
