//! The angular bandwidth B_θ(θ_o) of the outgoing Fresnel term, in cycles per radian
//! (Milaenen et al. 2019, §3.1, "Angular Variation").
//!
//! Every model of `sss-bssrdf` leaves the medium through the factor F_t(η, cos θ_o) (Jensen et
//! al. 2001, Eq. 5; Frisvad et al. 2014 likewise), so the angular variation of the outgoing
//! radiance is that of g(θ) = F_t(η, cos θ) for |θ| < π/2 and 0 beyond the horizon. Its local
//! bandwidth around θ_o comes from a windowed (short-time) Fourier transform: g(θ) · w(θ − θ_o)
//! with a Gaussian window w of standard deviation [`AngularOptions::window_rad`], sampled on
//! [`AngularOptions::samples`] points over a zero-padded period of [`AngularOptions::period_rad`]
//! radians, transformed with [`rustfft`], and B_θ(θ_o) is the frequency below which
//! [`AngularOptions::energy_fraction`] of the discrete power spectrum lies (|k| accumulated from
//! DC outward, both signs together; bin k's energy is spread evenly over (k − ½, k + ½]).
//!
//! The window sets a floor: for a flat g the result is the window's own bandwidth, which for a
//! Gaussian of standard deviation σ_w is erf⁻¹(f)/(2π σ_w) at energy fraction f (≈ 0.2206/σ_w,
//! 2.21 cycles/rad for the default σ_w = 0.1 rad and f = 0.95). Towards grazing angles the window
//! reaches the horizon, where F_t falls to 0 with a kink, and B_θ grows: that is the effect §3.1
//! tabulates θ_o for. The table holds B_θ at [`AngularOptions::table_size`] evenly spaced
//! θ_o ∈ [0, π/2]; [`AngularTable::cycles_per_radian`] interpolates linearly.

use crate::BandwidthError;
use crate::spectrum::{DEFAULT_ENERGY_FRACTION, check_fraction};
use rustfft::FftPlanner;
use rustfft::num_complex::Complex;
use sss_bssrdf::fresnel::ft_dielectric;
use std::f64::consts::FRAC_PI_2;

/// How B_θ is tabulated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AngularOptions {
    /// Energy fraction below B_θ, in (0, 1). Default 0.95.
    pub energy_fraction: f64,
    /// Standard deviation of the Gaussian window (radians). Default 0.1; in (0, 1].
    pub window_rad: f64,
    /// Length of the zero-padded period (radians); sets the frequency resolution 1/period.
    /// Default 16π (resolution 0.02 cycles/rad). At least 2π.
    pub period_rad: f64,
    /// Samples over the period. Default 8192 (step 6 mrad). At least 256.
    pub samples: usize,
    /// Table entries over θ_o ∈ [0, π/2]. Default 91 (1° apart). At least 2.
    pub table_size: usize,
}

impl Default for AngularOptions {
    fn default() -> Self {
        AngularOptions {
            energy_fraction: DEFAULT_ENERGY_FRACTION,
            window_rad: 0.1,
            period_rad: 16.0 * std::f64::consts::PI,
            samples: 8192,
            table_size: 91,
        }
    }
}

impl AngularOptions {
    fn check(&self) -> Result<(), BandwidthError> {
        check_fraction(self.energy_fraction)?;
        if !(self.window_rad > 0.0 && self.window_rad <= 1.0) {
            return Err(BandwidthError::InvalidArgument(format!(
                "window {} rad: must be in (0, 1]",
                self.window_rad
            )));
        }
        if !(self.period_rad >= std::f64::consts::TAU) || !self.period_rad.is_finite() {
            return Err(BandwidthError::InvalidArgument(format!(
                "period {} rad: must be finite and >= 2π",
                self.period_rad
            )));
        }
        if !(256..=1 << 20).contains(&self.samples) {
            return Err(BandwidthError::InvalidArgument(format!(
                "{} samples: must be in 256..=2^20",
                self.samples
            )));
        }
        if !(2..=100_000).contains(&self.table_size) {
            return Err(BandwidthError::InvalidArgument(format!(
                "table size {}: must be in 2..=100000",
                self.table_size
            )));
        }
        Ok(())
    }
}

/// Windowed-transform bandwidth (cycles per radian) of `g(θ)` around `theta0` (see the module
/// docs); `g` is sampled on the period centred on `theta0`. 0 when the windowed signal is 0.
/// Errors on invalid options or a non-finite sample.
pub fn windowed_bandwidth_cycles_per_radian(
    g: impl Fn(f64) -> f64,
    theta0: f64,
    opts: &AngularOptions,
) -> Result<f64, BandwidthError> {
    opts.check()?;
    if !theta0.is_finite() {
        return Err(BandwidthError::InvalidArgument(format!(
            "window centre {theta0} rad: must be finite"
        )));
    }
    let mut planner = FftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(opts.samples);
    windowed(&g, theta0, opts, fft.as_ref())
}

fn windowed(
    g: &impl Fn(f64) -> f64,
    theta0: f64,
    opts: &AngularOptions,
    fft: &dyn rustfft::Fft<f64>,
) -> Result<f64, BandwidthError> {
    let m = opts.samples;
    let h = opts.period_rad / m as f64;
    let inv_two_var = 1.0 / (2.0 * opts.window_rad * opts.window_rad);
    let mut data: Vec<Complex<f64>> = (0..m)
        .map(|i| {
            let offset = if i < m.div_ceil(2) {
                i as f64
            } else {
                i as f64 - m as f64
            } * h;
            let v = g(theta0 + offset);
            Complex::new(v * (-offset * offset * inv_two_var).exp(), 0.0)
        })
        .collect();
    if let Some(bad) = data.iter().position(|c| !c.re.is_finite()) {
        return Err(BandwidthError::InvalidArgument(format!(
            "the angular signal is not finite at sample {bad}"
        )));
    }
    fft.process(&mut data);
    // Power by |k|, both signs together.
    let half = m / 2;
    let mut shells = vec![0.0f64; half + 1];
    for (i, c) in data.iter().enumerate() {
        shells[i.min(m - i)] += c.norm_sqr();
    }
    let total: f64 = shells.iter().sum();
    if !(total > 0.0) || !total.is_finite() {
        return Ok(0.0);
    }
    let target = opts.energy_fraction * total;
    let mut cum = 0.0;
    for (k, &e) in shells.iter().enumerate() {
        if cum + e >= target && e > 0.0 {
            // Bin k's energy spread evenly over (k − ½, k + ½]; DC's over [0, ½].
            let t = ((target - cum) / e).clamp(0.0, 1.0);
            let k_cross = if k == 0 { 0.5 * t } else { k as f64 - 0.5 + t };
            return Ok(k_cross / opts.period_rad);
        }
        cum += e;
    }
    Ok(half as f64 / opts.period_rad)
}

/// B_θ(θ_o) in cycles per radian, tabulated over θ_o ∈ [0, π/2] for one relative index of
/// refraction η (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct AngularTable {
    eta: f64,
    values: Vec<f64>,
}

impl AngularTable {
    /// The table of the outgoing Fresnel transmittance F_t(η, cos θ_o) of a medium of relative
    /// index `eta` (inside over outside; light leaving sees 1/η, and F_t is symmetric in that
    /// sense: [`ft_dielectric`] is evaluated for the ray arriving from outside, which by
    /// reciprocity of the dielectric interface equals the transmittance of the ray leaving along
    /// θ_o). Errors on η not finite and > 0 and on invalid options.
    pub fn new(eta: f64, opts: &AngularOptions) -> Result<Self, BandwidthError> {
        opts.check()?;
        if !(eta > 0.0) || !eta.is_finite() {
            return Err(BandwidthError::InvalidArgument(format!(
                "eta {eta}: must be finite and > 0"
            )));
        }
        Self::from_signal(
            |theta: f64| {
                if theta.abs() < FRAC_PI_2 {
                    ft_dielectric(theta.cos(), eta)
                } else {
                    0.0
                }
            },
            eta,
            opts,
        )
    }

    /// The table of an arbitrary angular signal `g(θ)` (θ in radians, any sign); `eta` is only
    /// recorded. For tests and for other outgoing terms.
    pub fn from_signal(
        g: impl Fn(f64) -> f64,
        eta: f64,
        opts: &AngularOptions,
    ) -> Result<Self, BandwidthError> {
        opts.check()?;
        let mut planner = FftPlanner::<f64>::new();
        let fft = planner.plan_fft_forward(opts.samples);
        let n = opts.table_size;
        let values = (0..n)
            .map(|i| {
                let theta = FRAC_PI_2 * i as f64 / (n - 1) as f64;
                windowed(&g, theta, opts, fft.as_ref())
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(AngularTable { eta, values })
    }

    /// The relative index of refraction the table was built for.
    pub fn eta(&self) -> f64 {
        self.eta
    }

    /// The tabulated values, at θ_o = (π/2) · i/(len − 1).
    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// B_θ(θ_o) in cycles per radian, linearly interpolated. θ_o is taken as |θ_o| and clamped
    /// to [0, π/2]; NaN gives the grazing (largest-angle) entry, the conservative choice.
    pub fn cycles_per_radian(&self, theta_o: f64) -> f64 {
        let n = self.values.len();
        let t = if theta_o.is_nan() {
            FRAC_PI_2
        } else {
            theta_o.abs().min(FRAC_PI_2)
        };
        let x = t / FRAC_PI_2 * (n - 1) as f64;
        let i = (x.floor() as usize).min(n - 2);
        let f = (x - i as f64).clamp(0.0, 1.0);
        self.values[i] * (1.0 - f) + self.values[i + 1] * f
    }

    /// B_θ at the outgoing cosine `cos_theta_o`: |cos θ_o| is used (a back-facing normal counts
    /// as front-facing, as in [`crate::transport`]), capped at 1; NaN gives grazing.
    pub fn cycles_per_radian_at_cos(&self, cos_theta_o: f64) -> f64 {
        if cos_theta_o.is_nan() {
            return self.cycles_per_radian(FRAC_PI_2);
        }
        self.cycles_per_radian(cos_theta_o.abs().min(1.0).acos())
    }
}
