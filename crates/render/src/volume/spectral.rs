//! Chromatic media without bias or runaway weights: each path samples its free-flight
//! distances in one channel (the hero, chosen uniformly), and every channel's estimate is
//! weighted by the balance heuristic over the three channels' sampling densities of the whole
//! path (one-sample multiple importance sampling over the choice of hero; Veach 1997 §9.2.4).
//! This is pbrt-v4's `VolPathIntegrator` bookkeeping (`beta`, `r_u`), which Cycles and
//! Mitsuba 3's `volpathmis` share.
//!
//! With hero h and path density p_k of the path had channel k sampled it, the estimate of
//! channel c is f_c / ((1/3) Σ_k p_k). The state keeps β_c = f_c/p_h and r_k = p_k/p_h, both
//! scaled by one common factor that cancels in the estimate β_c / mean_k r_k; after each event
//! the factor makes max_k r_k = 1, so nothing overflows or underflows however long the walk.
//! Since f_c ≤ p_c event by event (σ_s ≤ σ_t) and mean_k p_k ≥ p_c/3, no channel's weight
//! exceeds 3: no fireflies from colour.

use sss_bssrdf::Rgb;

/// The spectral weights of one path.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpectralWeight {
    /// The hero channel (0, 1, 2): free-flight distances are sampled with its σ_t.
    pub hero: usize,
    /// f_c / p_h per channel, times the common scale.
    beta: Rgb,
    /// p_k / p_h per channel, times the common scale (max 1 after each update).
    r: Rgb,
}

impl SpectralWeight {
    /// A new path whose distances are sampled in channel `hero` (must be 0, 1 or 2).
    pub fn new(hero: usize) -> Self {
        SpectralWeight {
            hero: hero.min(2),
            beta: [1.0; 3],
            r: [1.0; 3],
        }
    }

    /// The path's weight per channel: β_c / mean_k r_k (finite, non-negative, at most 3 times
    /// the product of the deterministic factors applied with [`Self::scale`]).
    pub fn weight(&self) -> Rgb {
        let mean = (self.r[0] + self.r[1] + self.r[2]) / 3.0;
        if !(mean > 0.0 && mean.is_finite()) {
            return [0.0; 3];
        }
        self.beta.map(|b| {
            let w = b / mean;
            if w.is_finite() && w > 0.0 { w } else { 0.0 }
        })
    }

    /// Multiplies the path's contribution by a factor common to all sampling choices (a Fresnel
    /// transmittance applied deterministically, a texture, a roulette survival 1/q).
    pub fn scale(&mut self, f: Rgb) {
        for c in 0..3 {
            self.beta[c] *= f[c];
        }
    }

    /// A collision (real scattering) at distance `t` drawn with density σ_t,h e^{−σ_t,h t}:
    /// channel c's path gains f_c = σ_s,c e^{−σ_t,c t} and density p_c = σ_t,c e^{−σ_t,c t}.
    pub fn scatter(&mut self, sigma_s: Rgb, sigma_t: Rgb, t: f64) {
        let h = self.hero;
        for c in 0..3 {
            // e^{−(σ_t,c − σ_t,h) t}: bounded above by e^{σ_t,h t}, and σ_t,h t is the sampled
            // optical depth (below 40 for any double in [0, 1)).
            let tr = (-(sigma_t[c] - sigma_t[h]) * t).exp();
            self.beta[c] *= sigma_s[c] / sigma_t[h] * tr;
            self.r[c] *= sigma_t[c] / sigma_t[h] * tr;
        }
        self.rescale();
    }

    /// The walk reached a surface at distance `t` without a collision, which has probability
    /// e^{−σ_t,k t} for each channel k (and contributes the same transmittance to f).
    pub fn pass(&mut self, sigma_t: Rgb, t: f64) {
        let h = self.hero;
        for c in 0..3 {
            let tr = (-(sigma_t[c] - sigma_t[h]) * t).exp();
            self.beta[c] *= tr;
            self.r[c] *= tr;
        }
        self.rescale();
    }

    /// Divides β and r by max_k r_k (the estimate is unchanged).
    fn rescale(&mut self) {
        let m = self.r[0].max(self.r[1]).max(self.r[2]);
        if m > 0.0 && m.is_finite() {
            for c in 0..3 {
                self.beta[c] /= m;
                self.r[c] /= m;
            }
        } else {
            self.beta = [0.0; 3];
            self.r = [1.0; 3];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The weight after one collision, written out: f_c / ((1/3) Σ_k p_k).
    #[test]
    fn one_collision_gives_the_balance_heuristic() {
        let s = [0.7, 0.5, 0.1];
        let t_ = [1.0, 2.0, 4.0];
        let t = 0.3;
        for hero in 0..3 {
            let mut w = SpectralWeight::new(hero);
            w.scatter(s, t_, t);
            let p: Vec<f64> = (0..3).map(|k| t_[k] * (-t_[k] * t).exp()).collect();
            let mean = p.iter().sum::<f64>() / 3.0;
            let got = w.weight();
            for c in 0..3 {
                let f = s[c] * (-t_[c] * t).exp();
                assert!((got[c] - f / mean).abs() < 1e-12 * f / mean, "{hero} {c}");
            }
        }
    }

    /// Averaged over the hero's uniform choice with each hero's own free-flight densities, the
    /// weighted estimate of a one-collision path equals f_c: ∫ Σ_h (1/3) p_h w = f.
    /// Checked by quadrature of the expectation over t for a two-event path.
    #[test]
    fn the_estimate_is_unbiased_over_the_hero() {
        let s = [0.9, 0.6, 0.2];
        let st = [1.0, 3.0, 9.0];
        // E[weight · 1{collision before L}] over hero and t, against ∫₀^L f_c(t) dt.
        let l = 0.7;
        let n = 20_000;
        let mut est = [0.0; 3];
        let mut want = [0.0; 3];
        for i in 0..n {
            let t = (i as f64 + 0.5) / n as f64 * l;
            let dt = l / n as f64;
            for c in 0..3 {
                want[c] += s[c] * (-st[c] * t).exp() * dt;
            }
            for hero in 0..3 {
                let mut w = SpectralWeight::new(hero);
                w.scatter(s, st, t);
                let p = st[hero] * (-st[hero] * t).exp();
                let wt = w.weight();
                for c in 0..3 {
                    est[c] += wt[c] * p / 3.0 * dt;
                }
            }
        }
        for c in 0..3 {
            assert!((est[c] - want[c]).abs() < 1e-9, "{c}: {est:?} {want:?}");
        }
    }

    /// Long walks neither overflow nor underflow, and no weight exceeds 3.
    #[test]
    fn long_walks_stay_finite_and_bounded() {
        let s = [0.999, 0.99, 0.5];
        let st = [1.0, 50.0, 0.01];
        let mut w = SpectralWeight::new(1);
        for i in 0..100_000 {
            w.scatter(s, st, 0.02 + (i % 7) as f64 * 0.01);
            if i % 3 == 0 {
                w.pass(st, 0.05);
            }
            let x = w.weight();
            assert!(
                x.iter().all(|v| v.is_finite() && *v >= 0.0 && *v <= 3.0),
                "{x:?}"
            );
        }
    }
}
