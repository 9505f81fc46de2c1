//! The directional albedo of a half-space, A(θ): the fraction of the light arriving at angle θ
//! from the normal that the medium sends back out through its boundary (the entry's Fresnel
//! loss included, the specular reflection not), from the crate's own random walk
//! ([`crate::monte_carlo`]) started at oblique incidence.
//!
//! # Why
//! A separable radial model writes S = W_i(θ_i) R_d(r) W_o(θ_o) with W_i = F_t(η, cos θ_i) and
//! W_o = F_t(η, cos θ_o)/(cπ) (pbrt 3rd ed. §11.4.2): on a half-space under a light at θ_i it
//! returns the albedo R_tot F_t(θ_i) and leaves it in the lobe F_t(θ_o)/(cπ). Real transport
//! returns more at oblique incidence (the light enters shallower) and leaves in a flatter
//! lobe (single scattering's μ₀/(μ₀ + μ)); `cargo xtask compare --deficit` measures both
//! against volumetric path tracing. A reciprocal separable approximation that keeps the
//! true albedo is (the same form as the Fresnel one, with A in place of R_tot F_t):
//!
//! W_i(θ) = F_t(η, 1) A(θ)/A(0°),  W_o(θ) = A(θ)/(π Ā),  Ā = 2∫₀¹ A(μ) μ dμ,
//!
//! so that normal incidence is unchanged, ∫ W_o cos θ dω = 1 (every bit of the profile leaves),
//! and under uniform illumination a half-space returns exactly A(θ_o) towards every θ_o (by
//! reciprocity that is the true radiance there, whatever the lobe of each incidence).
//!
//! # The walk
//! For each node μ_k = cos θ_k of a uniform grid, photons enter at the origin along the
//! direction refracted from θ_k (Snell, η = the medium's index) with weight 1 and walk as in
//! [`crate::monte_carlo::simulate`]; A(μ_k) = F_t(η, μ_k) × the mean returned weight, per
//! channel, with its standard error. One walk at the largest albedo serves the three channels
//! (a half-space has no length of its own, so a channel of albedo α returns Σ weight ·
//! (α/α_max)ⁿ over the walk's escapes after n collisions: the condensed Monte Carlo of Graaff
//! et al. 1993). A(0) = 0 (grazing light is all reflected). Seeded per (seed, chunk) through
//! SplitMix64, the same streams at every node, and summed in chunk order: the same table for
//! any thread count.

use crate::fresnel::ft_dielectric;
use crate::monte_carlo::condensed_escapes;
use crate::{BssrdfError, DVec3, Medium, Rgb};
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;
use sss_util::splitmix64;
use std::sync::{Arc, Mutex, OnceLock};

/// Nodes of the μ grid after μ = 0 (so μ = 1/16, 2/16, ..., 1).
pub const NODES: usize = 16;

/// Photons per node of [`DirectionalAlbedo::cached`].
pub const PHOTONS: u64 = 8192;

/// Photons of one chunk (one RNG stream).
const CHUNK: u64 = 1024;

/// A(μ) of a medium on the grid μ = 0, 1/16, ..., 1, per channel.
#[derive(Clone, Debug, PartialEq)]
pub struct DirectionalAlbedo {
    /// The grid, μ = k/16 for k = 0..=16.
    pub mu: Vec<f64>,
    /// A at each node (A(0) = 0): F_t(η, μ) times the cubic fitted to the nodes' returned
    /// fractions.
    pub albedo: Vec<Rgb>,
    /// The standard error of each node's own estimate (the fitted value's is smaller).
    pub se: Vec<Rgb>,
    /// The white-sky albedo Ā = 2∫₀¹ A(μ) μ dμ of the piecewise-linear A.
    pub white: Rgb,
}

impl DirectionalAlbedo {
    /// A(μ) of `medium` from `photons` photons per node (one condensed walk serves the three
    /// channels; every node walks the same random numbers, so the table's shape A(μ)/A(1)
    /// is far less noisy than each node).
    pub fn simulate(medium: &Medium, photons: u64, seed: u64) -> Result<Self, BssrdfError> {
        if photons == 0 {
            return Err(BssrdfError::InvalidArgument(
                "photons must be at least 1".into(),
            ));
        }
        Ok(Self::walk(medium, photons, seed))
    }

    /// [`Self::simulate`] for `photons` ≥ 1.
    fn walk(medium: &Medium, photons: u64, seed: u64) -> Self {
        let eta = medium.eta();
        let albedos: Rgb = std::array::from_fn(|c| medium.albedo(c).clamp(0.0, 1.0));
        // The walk runs at the largest albedo; the other channels are reweighted by
        // (α_c/α_max)ⁿ after n collisions.
        let top = albedos.iter().fold(0.0f64, |a, &b| a.max(b));
        let rel: Rgb = std::array::from_fn(|c| if top > 0.0 { albedos[c] / top } else { 0.0 });
        let mu: Vec<f64> = (0..=NODES).map(|k| k as f64 / NODES as f64).collect();
        let chunks = photons.div_ceil(CHUNK);
        let items: Vec<(usize, u64)> = (1..=NODES)
            .flat_map(|k| (0..chunks).map(move |j| (k, j)))
            .collect();
        // Per item: Σ and Σ² over its photons of each channel's returned weight.
        let sums: Vec<([f64; 3], [f64; 3])> = items
            .par_iter()
            .map(|&(k, j)| {
                let n = CHUNK.min(photons - j * CHUNK);
                let h = splitmix64(seed ^ 0x5EED_A16B_ED00_0000);
                let h = splitmix64(h ^ j.wrapping_mul(0xA076_1D64_78BD_642F));
                let mut rng = Pcg64Mcg::seed_from_u64(h);
                let start = refracted(mu[k], eta);
                let (mut s, mut s2) = ([0.0; 3], [0.0; 3]);
                for _ in 0..n {
                    let mut w = [0.0; 3];
                    condensed_escapes(top, medium.g(), eta, start, &mut rng, &mut |e, x| {
                        let e = e.min(i32::MAX as u64) as i32;
                        for c in 0..3 {
                            w[c] += x * if rel[c] == 1.0 { 1.0 } else { rel[c].powi(e) };
                        }
                    });
                    for c in 0..3 {
                        s[c] += w[c];
                        s2[c] += w[c] * w[c];
                    }
                }
                (s, s2)
            })
            .collect();
        let mut tot = vec![([0.0; 3], [0.0; 3]); NODES + 1];
        for (i, &(k, _)) in items.iter().enumerate() {
            for c in 0..3 {
                tot[k].0[c] += sums[i].0[c];
                tot[k].1[c] += sums[i].1[c];
            }
        }
        let mut albedo = vec![[0.0; 3]; NODES + 1];
        let mut se = vec![[0.0; 3]; NODES + 1];
        let n = photons as f64;
        // Per node and channel: the mean returned weight per entering photon and its error.
        let mut per_entering = vec![[0.0; 3]; NODES + 1];
        for k in 1..=NODES {
            for c in 0..3 {
                let (s, s2) = (tot[k].0[c], tot[k].1[c]);
                let var = if n > 1.0 {
                    ((s2 - s * s / n) / (n - 1.0)).max(0.0)
                } else {
                    0.0
                };
                per_entering[k][c] = s / n;
                se[k][c] = (var / n).sqrt();
            }
        }
        // The returned fraction of what enters varies slowly with the angle (from the
        // half-space's total at normal incidence to somewhat more at grazing incidence): a
        // cubic in μ fitted to the 16 nodes by weighted least squares carries the table, with
        // every node's photons behind each value (the nodes alone are 4× noisier).
        for c in 0..3 {
            let ys: Vec<(f64, f64, f64)> = (1..=NODES)
                .map(|k| (mu[k], per_entering[k][c], se[k][c]))
                .collect();
            let fit = cubic_fit(&ys);
            for k in 1..=NODES {
                let ft = ft_dielectric(mu[k], eta);
                let y = fit.map_or(per_entering[k][c], |p| {
                    p[0] + mu[k] * (p[1] + mu[k] * (p[2] + mu[k] * p[3]))
                });
                albedo[k][c] = ft * y.max(0.0);
                se[k][c] *= ft;
            }
        }
        let white = white_sky(&mu, &albedo);
        DirectionalAlbedo {
            mu,
            albedo,
            se,
            white,
        }
    }

    /// The table of `medium` at [`PHOTONS`] photons and a fixed seed, computed once per
    /// process for each distinct (σ_a, σ_s, g, η) and shared.
    pub fn cached(medium: &Medium) -> Arc<Self> {
        type Cache = Mutex<Vec<([u64; 8], Arc<DirectionalAlbedo>)>>;
        static CACHE: OnceLock<Cache> = OnceLock::new();
        let key = medium.bits();
        let cache = CACHE.get_or_init(|| Mutex::new(Vec::new()));
        if let Some((_, t)) = cache
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .iter()
            .find(|(k, _)| *k == key)
        {
            return t.clone();
        }
        let t = Arc::new(Self::walk(medium, PHOTONS.max(1), 1));
        let mut guard = cache.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((_, found)) = guard.iter().find(|(k, _)| *k == key) {
            return found.clone();
        }
        guard.push((key, t.clone()));
        t
    }

    /// A(μ) by linear interpolation between the nodes (μ clamped to [0, 1]; 0 for NaN).
    pub fn at(&self, mu: f64) -> Rgb {
        if !(mu > 0.0) {
            return [0.0; 3];
        }
        let x = mu.min(1.0) * NODES as f64;
        let k = (x.floor() as usize).min(NODES - 1);
        let t = x - k as f64;
        let (a, b) = (self.albedo[k], self.albedo[k + 1]);
        std::array::from_fn(|c| a[c] + t * (b[c] - a[c]))
    }

    /// The entry weight W_i(μ) = F_t(η, 1) A(μ)/A(1) per channel (0 where A(1) is 0).
    pub fn entry_weight(&self, mu: f64, eta: f64) -> Rgb {
        let a = self.at(mu);
        let a1 = self.albedo[NODES];
        let ft1 = ft_dielectric(1.0, eta);
        std::array::from_fn(|c| if a1[c] > 0.0 { ft1 * a[c] / a1[c] } else { 0.0 })
    }

    /// The exit weight W_o(μ) = A(μ)/(π Ā) per channel (0 where Ā is 0): ∫ W_o cos θ dω = 1.
    pub fn exit_weight(&self, mu: f64) -> Rgb {
        let a = self.at(mu);
        std::array::from_fn(|c| {
            if self.white[c] > 0.0 {
                a[c] / (std::f64::consts::PI * self.white[c])
            } else {
                0.0
            }
        })
    }
}

/// The direction into the half-space z < 0 refracted from light arriving at cos θ = `mu`
/// (in the x–z plane): sin θ_t = sin θ/η.
fn refracted(mu: f64, eta: f64) -> DVec3 {
    let sin_i = (1.0 - mu * mu).max(0.0).sqrt();
    let sin_t = (sin_i / eta).min(1.0);
    let cos_t = (1.0 - sin_t * sin_t).max(0.0).sqrt();
    DVec3::new(sin_t, 0.0, -cos_t)
}

/// The cubic c₀ + c₁μ + c₂μ² + c₃μ³ through points (μ, y, σ) by weighted least squares
/// (weights 1/σ², σ floored at 10⁻⁶ of the largest |y| so exact data stay finite): the
/// normal equations solved by Gaussian elimination with partial pivoting. None if they are
/// singular (fewer than four distinct μ).
fn cubic_fit(points: &[(f64, f64, f64)]) -> Option<[f64; 4]> {
    let top = points.iter().fold(0.0f64, |a, p| a.max(p.1.abs()));
    let floor = (1e-6 * top).max(1e-300);
    let mut m = [[0.0f64; 5]; 4];
    for &(x, y, s) in points {
        let w = 1.0 / s.max(floor).powi(2);
        let pw = [1.0, x, x * x, x * x * x];
        for i in 0..4 {
            for j in 0..4 {
                m[i][j] += w * pw[i] * pw[j];
            }
            m[i][4] += w * pw[i] * y;
        }
    }
    for col in 0..4 {
        let piv = (col..4).max_by(|&a, &b| m[a][col].abs().total_cmp(&m[b][col].abs()))?;
        if !(m[piv][col].abs() > 1e-300) {
            return None;
        }
        m.swap(col, piv);
        for r in 0..4 {
            if r != col {
                let f = m[r][col] / m[col][col];
                for k in col..5 {
                    m[r][k] -= f * m[col][k];
                }
            }
        }
    }
    let c: [f64; 4] = std::array::from_fn(|i| m[i][4] / m[i][i]);
    c.iter().all(|v| v.is_finite()).then_some(c)
}

/// 2∫₀¹ A(μ) μ dμ of the piecewise-linear A through the nodes, exactly: on [μ_a, μ_b] the
/// integral of the line through (μ_a, A_a), (μ_b, A_b) times μ is h (A_a(2μ_a + μ_b) +
/// A_b(μ_a + 2μ_b))/6.
fn white_sky(mu: &[f64], a: &[Rgb]) -> Rgb {
    let mut w = [0.0; 3];
    for k in 0..mu.len().saturating_sub(1) {
        let (ma, mb) = (mu[k], mu[k + 1]);
        let h = mb - ma;
        for c in 0..3 {
            w[c] += h * (a[k][c] * (2.0 * ma + mb) + a[k + 1][c] * (ma + 2.0 * mb)) / 6.0;
        }
    }
    w.map(|v| 2.0 * v)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Chandrasekhar's H function of an isotropic scatterer of albedo ω, by the iteration
    /// 1/H(μ) = √(1 − ω) + (ω/2) ∫₀¹ μ' H(μ')/(μ + μ') dμ' (Chandrasekhar 1960, Eq. V.(13) in
    /// the form of Bosma & de Rooij 1983), on a Gauss–Legendre grid; then H at `mu`.
    fn h_function(omega: f64, mu: f64) -> f64 {
        let (x, wq) = gauss_legendre_01(64);
        // The right-hand side at μ for the current H on the grid.
        let inverse = |m: f64, h: &[f64]| {
            let s: f64 = x
                .iter()
                .zip(&wq)
                .zip(h)
                .map(|((&m2, &w2), &h2)| w2 * m2 * h2 / (m + m2))
                .sum();
            1.0 / ((1.0 - omega).sqrt() + 0.5 * omega * s)
        };
        let mut h = vec![1.0; x.len()];
        for _ in 0..500 {
            h = x.iter().map(|&m| inverse(m, &h)).collect();
        }
        inverse(mu, &h)
    }

    /// Gauss–Legendre nodes and weights on [0, 1] (Newton on P_n).
    fn gauss_legendre_01(n: usize) -> (Vec<f64>, Vec<f64>) {
        // (P_n(t), P_n'(t)) by the three-term recurrence.
        let legendre = |t: f64| {
            let (mut p0, mut p1) = (1.0, t);
            for k in 2..=n {
                let p2 = ((2 * k - 1) as f64 * t * p1 - (k - 1) as f64 * p0) / k as f64;
                p0 = p1;
                p1 = p2;
            }
            (p1, n as f64 * (t * p1 - p0) / (t * t - 1.0))
        };
        let mut x = Vec::new();
        let mut w = Vec::new();
        for i in 0..n {
            let mut t = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            for _ in 0..100 {
                let (p, dp) = legendre(t);
                let dt = p / dp;
                t -= dt;
                if dt.abs() < 1e-15 {
                    break;
                }
            }
            let (_, dp) = legendre(t);
            x.push(0.5 * (t + 1.0));
            w.push(1.0 / ((1.0 - t * t) * dp * dp));
        }
        (x, w)
    }

    /// Index-matched, isotropic: the plane albedo has the closed form
    /// A(μ₀) = 1 − H(μ₀) √(1 − ω) (Chandrasekhar 1960, §V; van de Hulst 1980), which the walk
    /// must reproduce at every node within 4 standard errors, in each channel of a medium whose
    /// channels differ (ω = 0.5, 0.9, 0.99: one walk at the largest albedo, the others
    /// reweighted by (ω_c/ω_max)ⁿ).
    #[test]
    fn an_index_matched_albedo_is_chandrasekhars() {
        let omega = [0.5, 0.9, 0.99];
        let m = Medium::new(omega.map(|w| 1.0 - w), omega, 0.0, 1.0).unwrap();
        let t = DirectionalAlbedo::simulate(&m, 100_000, 3).unwrap();
        assert_eq!(t.albedo[0], [0.0; 3]);
        for (c, &w) in omega.iter().enumerate() {
            for k in [1, 4, 8, 12, 16] {
                let want = 1.0 - h_function(w, t.mu[k]) * (1.0 - w).sqrt();
                let (got, se) = (t.albedo[k][c], t.se[k][c]);
                assert!(
                    se > 0.0 && se < 0.01 * want,
                    "ω {w}, μ {}: se {se}",
                    t.mu[k]
                );
                assert!(
                    (got - want).abs() < 4.0 * se,
                    "ω {w}, μ {}: {got} ± {se}, closed form {want}",
                    t.mu[k]
                );
            }
        }
    }

    /// Where A(μ) = F_t(η, μ) (a medium that absorbs nothing returns all that enters), the
    /// entry weight is F_t itself and the exit weight F_t/(πĀ) with Ā = 2∫F_t μ dμ = c, the
    /// normalisation of today's F_t/(cπ), to the interpolation's error.
    #[test]
    fn with_fresnels_albedo_the_weights_are_fresnels() {
        let eta = 1.3;
        let mu: Vec<f64> = (0..=NODES).map(|k| k as f64 / NODES as f64).collect();
        let albedo: Vec<Rgb> = mu
            .iter()
            .map(|&m| [if m > 0.0 { ft_dielectric(m, eta) } else { 0.0 }; 3])
            .collect();
        let white = white_sky(&mu, &albedo);
        let t = DirectionalAlbedo {
            mu: mu.clone(),
            se: vec![[0.0; 3]; NODES + 1],
            albedo,
            white,
        };
        for &m in &mu[1..] {
            let ft = ft_dielectric(m, eta);
            assert!((t.entry_weight(m, eta)[1] - ft).abs() < 1e-12);
            let wo = t.exit_weight(m)[1];
            assert!((wo - ft / (std::f64::consts::PI * white[1])).abs() < 1e-12);
        }
        let c = crate::fresnel_normalization(eta);
        assert!((white[0] - c).abs() < 4e-3, "{} vs {c}", white[0]);
        // Ā is the exact integral of the interpolant: a fine midpoint rule agrees.
        let n = 100_000;
        let fine: f64 = (0..n)
            .map(|i| {
                let m = (i as f64 + 0.5) / n as f64;
                2.0 * t.at(m)[0] * m / n as f64
            })
            .sum();
        assert!((white[0] - fine).abs() < 1e-9);
    }

    /// The fit reproduces a cubic exactly and weighs points by 1/σ².
    #[test]
    fn the_cubic_fit_is_exact_on_a_cubic() {
        let f = |x: f64| 0.3 - 0.2 * x + 0.5 * x * x - 0.1 * x * x * x;
        let pts: Vec<(f64, f64, f64)> = (1..=16)
            .map(|k| {
                let x = k as f64 / 16.0;
                (x, f(x), 0.01 * (1.0 + x))
            })
            .collect();
        let c = cubic_fit(&pts).unwrap();
        for (got, want) in c.iter().zip([0.3, -0.2, 0.5, -0.1]) {
            assert!((got - want).abs() < 1e-10, "{got} vs {want}");
        }
        // A constant through two groups of points: the weighted mean.
        let pts = [
            (0.1, 1.0, 1.0),
            (0.2, 1.0, 1.0),
            (0.3, 1.0, 1.0),
            (0.4, 1.0, 1.0),
            (0.5, 3.0, 1e9),
            (0.6, 3.0, 1e9),
            (0.7, 3.0, 1e9),
            (0.8, 3.0, 1e9),
        ];
        let c = cubic_fit(&pts).unwrap();
        let v = c[0] + 0.25 * (c[1] + 0.25 * (c[2] + 0.25 * c[3]));
        assert!((v - 1.0).abs() < 1e-6, "{v}");
        assert!(cubic_fit(&[(0.5, 1.0, 0.1); 6]).is_none());
    }

    /// Interpolation between nodes is linear; out of range is clamped; NaN is 0.
    #[test]
    fn interpolation_and_edges() {
        let mut t = DirectionalAlbedo {
            mu: (0..=NODES).map(|k| k as f64 / NODES as f64).collect(),
            albedo: (0..=NODES)
                .map(|k| [k as f64, 2.0 * k as f64, 0.0])
                .collect(),
            se: vec![[0.0; 3]; NODES + 1],
            white: [0.0; 3],
        };
        t.white = white_sky(&t.mu, &t.albedo);
        // A(μ) = 16 μ in red: Ā = 2∫16 μ² dμ = 32/3, exactly for a line.
        assert!((t.white[0] - 32.0 / 3.0).abs() < 1e-12);
        assert!((t.at(0.53125)[0] - 8.5).abs() < 1e-12);
        assert_eq!(t.at(2.0), t.albedo[NODES]);
        assert_eq!(t.at(f64::NAN), [0.0; 3]);
        assert_eq!(t.at(-1.0), [0.0; 3]);
        // A zero channel gives zero weights, not NaN.
        assert_eq!(t.entry_weight(0.5, 1.3)[2], 0.0);
        assert_eq!(t.exit_weight(0.5)[2], 0.0);
    }

    /// A photon count that leaves a short last chunk (1 025 = 1 024 + 1) is counted as given:
    /// the albedo at normal incidence still matches the closed form.
    #[test]
    fn a_short_last_chunk_counts_its_own_photons() {
        let omega = 0.9;
        let m = Medium::new([1.0 - omega; 3], [omega; 3], 0.0, 1.0).unwrap();
        let t = DirectionalAlbedo::simulate(&m, 1025, 4).unwrap();
        let want = 1.0 - h_function(omega, 1.0) * (1.0 - omega).sqrt();
        let (got, se) = (t.albedo[NODES][0], t.se[NODES][0]);
        assert!(
            (got - want).abs() < 5.0 * se,
            "{got} ± {se}, closed form {want}"
        );
    }

    /// The same table for any thread count.
    #[test]
    fn bit_identical_across_thread_counts() {
        let m = Medium::preset("skin1").unwrap();
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| DirectionalAlbedo::simulate(&m, 3000, 9).unwrap());
        let many = rayon::ThreadPoolBuilder::new()
            .num_threads(3)
            .build()
            .unwrap()
            .install(|| DirectionalAlbedo::simulate(&m, 3000, 9).unwrap());
        assert_eq!(one, many);
    }
}
