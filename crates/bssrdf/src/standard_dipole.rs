//! The standard dipole of Jensen, Marschner, Levoy and Hanrahan, *A Practical Model for
//! Subsurface Light Transport*, SIGGRAPH 2001 (§2.4).
//!
//! A positive point source at depth z_r = 1/σ'_t and a negative image source at height
//! z_v = z_r (1 + 4A/3) above the surface, A = (1 + F_dr)/(1 − F_dr), give
//!
//! R_d(r) = α'/(4π) Σ_{z ∈ {z_r, z_v}} z (1 + σ_tr d) e^{−σ_tr d} / d³,  d = √(r² + z²).
//!
//! Because d/dd [−e^{−σd}/d] = (1 + σd) e^{−σd}/d², every term has a closed-form radial
//! integral, and so does the tail mass beyond r:
//!
//! T(r) = ∫_r^∞ 2πr' R_d dr' = α'/2 Σ_z (z/d) e^{−σ_tr d},
//!
//! whose value at r = 0 is Jensen et al.'s total diffuse reflectance
//! R_d = α'/2 (1 + e^{−(4/3)A√(3(1−α'))}) e^{−√(3(1−α'))}. Sampling solves T(r) = (1−u)T(0)
//! exactly, starting from a per-channel guide table ([`TailTable`]). F_dr is the exact
//! internal diffuse Fresnel reflectance ([`crate::fresnel::diffuse_fresnel_reflectance`] at
//! 1/η) rather than the paper's polynomial fit (they agree to about 1 %).

use crate::radial::{ClosedFormTail, TailTable, distance};
use crate::{Bssrdf, Medium, ModelKind, fresnel};

/// Per-channel constants of the dipole.
#[derive(Clone, Copy, Debug)]
struct Channel {
    alpha_p: f64,
    sigma_tr: f64,
    z_r: f64,
    z_v: f64,
    total: f64,
}

impl Channel {
    fn term(&self, z: f64, r: f64) -> f64 {
        let d = distance(r, z);
        let s = self.sigma_tr * d;
        z * (1.0 + s) * (-s).exp() / (d * d * d)
    }

    fn rd(&self, r: f64) -> f64 {
        if self.alpha_p <= 0.0 {
            return 0.0;
        }
        let v = self.alpha_p / (4.0 * std::f64::consts::PI)
            * (self.term(self.z_r, r) + self.term(self.z_v, r));
        v.max(0.0)
    }
}

impl Channel {
    /// (R_d, R_d′, R_d″) in closed form. With d = √(r² + z²) and s = σ_tr d, each source's
    /// term T(d) = z (1 + s) e^{−s}/d³ has T′(d) = −z e^{−s} (s² + 3s + 3)/d⁴ and
    /// T″(d) = z e^{−s} (s³ + 5s² + 12s + 12)/d⁵ (differentiating Jensen et al. 2001 Eq. 4
    /// term by term), and d′(r) = r/d, d″(r) = z²/d³, so R′ = T′ r/d and
    /// R″ = T″ (r/d)² + T′ z²/d³ (the derivatives of the even function R_d(r), R′(0) = 0).
    fn derivatives(&self, r: f64) -> (f64, f64, f64) {
        if self.alpha_p <= 0.0 {
            return (0.0, 0.0, 0.0);
        }
        let k = self.alpha_p / (4.0 * std::f64::consts::PI);
        let (mut v, mut d1, mut d2) = (0.0, 0.0, 0.0);
        for z in [self.z_r, self.z_v] {
            let d = distance(r, z);
            let s = self.sigma_tr * d;
            let e = (-s).exp();
            let d3 = d * d * d;
            let t0 = z * (1.0 + s) * e / d3;
            let t1 = -z * e * (s * s + 3.0 * s + 3.0) / (d3 * d);
            let t2 = z * e * (s * (s * (s + 5.0) + 12.0) + 12.0) / (d3 * d * d);
            let (a, b) = (r / d, z * z / d3);
            v += t0;
            d1 += t1 * a;
            d2 += t2 * a * a + t1 * b;
        }
        (
            crate::finite_or_zero((k * v).max(0.0)),
            crate::finite_or_zero(k * d1),
            crate::finite_or_zero(k * d2),
        )
    }
}

impl ClosedFormTail for Channel {
    fn tail(&self, r: f64) -> f64 {
        let t = |z: f64| {
            let d = distance(r, z);
            z / d * (-self.sigma_tr * d).exp()
        };
        0.5 * self.alpha_p * (t(self.z_r) + t(self.z_v))
    }

    fn density(&self, r: f64) -> f64 {
        2.0 * std::f64::consts::PI * r * self.rd(r)
    }

    fn tail_and_density(&self, r: f64) -> (f64, f64) {
        // The same terms as `tail` and `rd`, sharing d and e^{−σ_tr d} per source.
        let (mut tail, mut flux) = (0.0, 0.0);
        for z in [self.z_r, self.z_v] {
            let d = distance(r, z);
            let s = self.sigma_tr * d;
            let e = (-s).exp();
            tail += z / d * e;
            flux += z * (1.0 + s) * e / (d * d * d);
        }
        if self.alpha_p <= 0.0 {
            return (0.0, 0.0);
        }
        let density = 0.5 * r * self.alpha_p * flux;
        (0.5 * self.alpha_p * tail, density.max(0.0))
    }

    fn total(&self) -> f64 {
        self.total
    }

    fn scale(&self) -> f64 {
        self.z_r
    }
}

/// The standard dipole of Jensen et al. 2001.
#[derive(Clone, Debug)]
pub struct StandardDipole {
    medium: Medium,
    ch: [Channel; 3],
    /// Guide tables for exact fast sampling ([`TailTable`]).
    tables: [TailTable; 3],
}

impl StandardDipole {
    /// Precomputes the per-channel constants of `medium`.
    pub fn new(medium: Medium) -> Self {
        let f_dr = fresnel::diffuse_fresnel_reflectance(1.0 / medium.eta());
        // F_dr < 1 for every finite η: normal incidence always transmits.
        let a = (1.0 + f_dr) / (1.0 - f_dr).max(1e-12);
        let ch = std::array::from_fn(|c| {
            let z_r = medium.reduced_mean_free_path(c);
            let mut channel = Channel {
                alpha_p: medium.reduced_albedo(c),
                sigma_tr: medium.sigma_tr(c),
                z_r,
                z_v: z_r * (1.0 + 4.0 * a / 3.0),
                total: 0.0,
            };
            channel.total = channel.tail(0.0).clamp(0.0, 1.0);
            channel
        });
        let tables = std::array::from_fn(|c| TailTable::new(&ch[c]));
        StandardDipole { medium, ch, tables }
    }

    /// The closed-form total diffuse reflectance of Jensen et al. 2001,
    /// α'/2 (1 + e^{−(4/3)A√(3(1−α'))}) e^{−√(3(1−α'))}, written in the paper's form (used by
    /// the tests to check the tail formula).
    pub fn total_closed_form(&self, ch: usize) -> f64 {
        let c = &self.ch[ch];
        let a = (c.z_v / c.z_r - 1.0) * 0.75;
        let s = (3.0 * (1.0 - c.alpha_p)).max(0.0).sqrt();
        0.5 * c.alpha_p * (1.0 + (-(4.0 / 3.0) * a * s).exp()) * (-s).exp()
    }
}

impl Bssrdf for StandardDipole {
    fn kind(&self) -> ModelKind {
        ModelKind::StandardDipole
    }
    fn medium(&self) -> &Medium {
        &self.medium
    }
    fn rd(&self, ch: usize, r: f64) -> f64 {
        self.ch[ch].rd(r.abs())
    }
    fn rd_derivatives(&self, ch: usize, r: f64) -> (f64, f64, f64) {
        self.ch[ch].derivatives(r.abs())
    }
    fn total_diffuse_reflectance(&self, ch: usize) -> f64 {
        self.ch[ch].total
    }
    fn sample_sr(&self, ch: usize, u: f64) -> f64 {
        self.tables[ch].sample(&self.ch[ch], u)
    }
    fn pdf_sr(&self, ch: usize, r: f64) -> f64 {
        self.ch[ch].pdf(r)
    }
    fn radius_for_energy(&self, ch: usize, fraction: f64) -> f64 {
        self.tables[ch].sample(&self.ch[ch], fraction.clamp(0.0, 1.0 - 1e-15))
    }
}
