//! Discrete power spectra of 2-D profiles and their energy bandwidth.
//!
//! A profile f(x, y) (any unit per mm², lengths in mm) is sampled on a square grid of
//! `cells × cells` points with spacing `step_mm`, centred on the origin with periodic wrap-around
//! (sample (i, j) sits at x = i·h for i < N/2 and at (i − N)·h otherwise, so the origin is sample
//! (0, 0) and no phase ramp is needed). A 2-D FFT ([`rustfft`], rows then columns) gives the
//! discrete spectrum F[k_x, k_y] at frequencies (k_x, k_y)/(N h) in **cycles per mm**, and the
//! discrete power spectrum |F|². Its energy is accumulated shell by shell in the radial frequency
//! ρ = √(k_x² + k_y²)/(N h), from DC outward, until `energy_fraction` of the total is reached: that
//! ρ is the bandwidth (Milaenen et al. 2019, §3.1 and §5: "the 95th percentile of the discrete
//! spectrum"). Each shell's energy is taken as spread evenly between the midpoints to its neighbouring
//! radii, so the result is a continuous function of the profile.
//!
//! Why a 2-D grid and not a 1-D Hankel transform: the directional dipole is not radially
//! symmetric (its profile depends on the direction of x_o − x_i relative to the refracted ray),
//! and the same code then serves every model; the energy fraction of a radial profile is the
//! 2-D one (weight 2πρ dρ), which a 2-D grid counts by construction. A 512² grid costs a few
//! milliseconds.
//!
//! For a Gaussian f = exp(−r²/(2σ²)) the continuous power spectrum is ∝ exp(−4π²σ²ρ²), whose
//! energy below ρ is 1 − exp(−4π²σ²ρ²), so ρ₉₅ = √(ln 20)/(2πσ); the tests check the grid against
//! it.

use crate::BandwidthError;
use rustfft::FftPlanner;
use rustfft::num_complex::Complex;

/// The default energy fraction defining a bandwidth (Milaenen et al. 2019, §5: 95 %).
pub const DEFAULT_ENERGY_FRACTION: f64 = 0.95;

/// Largest grid side accepted (4096² complex f64 samples = 256 MiB).
pub const MAX_CELLS: usize = 4096;

/// A square sampling grid: `cells × cells` samples `step_mm` apart, centred on the origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpectrumGrid {
    step_mm: f64,
    cells: usize,
}

impl SpectrumGrid {
    /// A grid of `cells × cells` samples with spacing `step_mm` (mm). Errors unless the step is
    /// finite and > 0 and 8 ≤ `cells` ≤ [`MAX_CELLS`]. The grid spans `cells · step_mm` mm, its
    /// frequency resolution is 1/(`cells · step_mm`) and its Nyquist frequency 1/(2 `step_mm`)
    /// cycles per mm.
    pub fn new(step_mm: f64, cells: usize) -> Result<Self, BandwidthError> {
        if !(step_mm > 0.0) || !step_mm.is_finite() {
            return Err(BandwidthError::InvalidArgument(format!(
                "grid step {step_mm} mm: must be finite and > 0"
            )));
        }
        if !(8..=MAX_CELLS).contains(&cells) {
            return Err(BandwidthError::InvalidArgument(format!(
                "grid of {cells} cells: must be in 8..={MAX_CELLS}"
            )));
        }
        Ok(SpectrumGrid { step_mm, cells })
    }

    /// Sample spacing (mm).
    pub fn step_mm(&self) -> f64 {
        self.step_mm
    }

    /// Samples per side.
    pub fn cells(&self) -> usize {
        self.cells
    }

    /// Half the side length, the largest |x| sampled (mm).
    pub fn half_extent_mm(&self) -> f64 {
        0.5 * self.cells as f64 * self.step_mm
    }

    /// Nyquist frequency 1/(2 step) in cycles per mm.
    pub fn nyquist_cycles_per_mm(&self) -> f64 {
        0.5 / self.step_mm
    }

    /// Coordinate (mm) of sample index `i` (wrap-around layout).
    fn coord(&self, i: usize) -> f64 {
        let n = self.cells;
        let signed = if i < n.div_ceil(2) {
            i as f64
        } else {
            i as f64 - n as f64
        };
        signed * self.step_mm
    }
}

/// Checks an energy fraction: finite, in (0, 1).
pub(crate) fn check_fraction(energy_fraction: f64) -> Result<(), BandwidthError> {
    if !(energy_fraction > 0.0 && energy_fraction < 1.0) {
        return Err(BandwidthError::InvalidArgument(format!(
            "energy fraction {energy_fraction}: must be in (0, 1)"
        )));
    }
    Ok(())
}

/// Energy bandwidth (cycles per mm) of the 2-D profile `profile(x_mm, y_mm)` sampled on `grid`:
/// the radial frequency below which `energy_fraction` of the discrete power spectrum lies (see
/// the module docs). A profile that is zero everywhere has bandwidth 0. Errors on a fraction
/// outside (0, 1) and on a non-finite sample.
pub fn bandwidth_2d_cycles_per_mm(
    profile: impl Fn(f64, f64) -> f64,
    grid: &SpectrumGrid,
    energy_fraction: f64,
) -> Result<f64, BandwidthError> {
    smoothed_bandwidth_2d_cycles_per_mm(profile, grid, energy_fraction, 0.0)
}

/// As [`bandwidth_2d_cycles_per_mm`], of the profile convolved with a normalised Gaussian of
/// standard deviation `smoothing_mm` (0: none): the power spectrum is multiplied by
/// exp(−4π² s² ρ²) before the energy is accumulated. Errors on a negative or non-finite
/// smoothing.
pub fn smoothed_bandwidth_2d_cycles_per_mm(
    profile: impl Fn(f64, f64) -> f64,
    grid: &SpectrumGrid,
    energy_fraction: f64,
    smoothing_mm: f64,
) -> Result<f64, BandwidthError> {
    check_fraction(energy_fraction)?;
    if !(smoothing_mm >= 0.0) || !smoothing_mm.is_finite() {
        return Err(BandwidthError::InvalidArgument(format!(
            "smoothing {smoothing_mm} mm: must be finite and >= 0"
        )));
    }
    let n = grid.cells;
    let mut data = vec![Complex::new(0.0, 0.0); n * n];
    let coords: Vec<f64> = (0..n).map(|i| grid.coord(i)).collect();
    let mut peak = 0.0f64;
    for (j, &y) in coords.iter().enumerate() {
        for (i, &x) in coords.iter().enumerate() {
            let v = profile(x, y);
            if !v.is_finite() {
                return Err(BandwidthError::NonFiniteProfile { x_mm: x, y_mm: y });
            }
            peak = peak.max(v.abs());
            data[j * n + i] = Complex::new(v, 0.0);
        }
    }
    if peak == 0.0 {
        return Ok(0.0);
    }
    // Normalise to a peak of 1 so that squaring neither overflows nor underflows for profiles
    // of any magnitude (the fraction is scale invariant).
    let inv = 1.0 / peak;
    for c in &mut data {
        c.re *= inv;
    }
    fft_2d(&mut data, n);
    // exp(−4π² s² ρ²) with ρ = k/(N h): per unit of k² the exponent is −4π² (s/(N h))².
    let a = 4.0 * std::f64::consts::PI.powi(2) * (smoothing_mm / (n as f64 * grid.step_mm)).powi(2);
    let fraction_radius = energy_radius(&data, n, energy_fraction, a);
    Ok(fraction_radius / (n as f64 * grid.step_mm))
}

/// Energy bandwidth (cycles per mm) of a radially symmetric profile `profile(r_mm)`, sampled
/// on the 2-D `grid` as f(√(x² + y²)); see [`bandwidth_2d_cycles_per_mm`].
pub fn radial_bandwidth_cycles_per_mm(
    profile: impl Fn(f64) -> f64,
    grid: &SpectrumGrid,
    energy_fraction: f64,
) -> Result<f64, BandwidthError> {
    bandwidth_2d_cycles_per_mm(|x, y| profile(x.hypot(y)), grid, energy_fraction)
}

/// In-place 2-D forward FFT of a row-major `n × n` array.
fn fft_2d(data: &mut [Complex<f64>], n: usize) {
    let mut planner = FftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(n);
    // Rows.
    fft.process(data);
    // Columns, through a transpose.
    let mut t = vec![Complex::new(0.0, 0.0); n * n];
    transpose(data, &mut t, n);
    fft.process(&mut t);
    transpose(&t, data, n);
}

fn transpose(src: &[Complex<f64>], dst: &mut [Complex<f64>], n: usize) {
    const B: usize = 32;
    for jb in (0..n).step_by(B) {
        for ib in (0..n).step_by(B) {
            for j in jb..(jb + B).min(n) {
                for i in ib..(ib + B).min(n) {
                    dst[i * n + j] = src[j * n + i];
                }
            }
        }
    }
}

/// The radius, in units of the frequency step, holding `fraction` of Σ|F|²: power histogrammed
/// by the exact integer key k_x² + k_y², accumulated from DC outward, interpolated linearly in
/// radius inside the shell that crosses the target (see the comment inside).
fn energy_radius(spectrum: &[Complex<f64>], n: usize, fraction: f64, smoothing: f64) -> f64 {
    let half = n / 2;
    let max_key = 2 * half * half;
    let mut shells = vec![0.0f64; max_key + 1];
    let mut total = 0.0;
    for j in 0..n {
        let ky = j.min(n - j);
        for i in 0..n {
            let kx = i.min(n - i);
            let key = kx * kx + ky * ky;
            let p = spectrum[j * n + i].norm_sqr() * (-smoothing * key as f64).exp();
            shells[key] += p;
            total += p;
        }
    }
    if !(total > 0.0) || !total.is_finite() {
        return 0.0;
    }
    let target = fraction * total;
    // The occupied shells in order; shell j's energy is spread evenly between the midpoints to
    // its neighbours (DC's from 0 to half the first non-zero radius).
    let occupied: Vec<(f64, f64)> = shells
        .iter()
        .enumerate()
        .filter(|&(_, &e)| e > 0.0)
        .map(|(key, &e)| ((key as f64).sqrt(), e))
        .collect();
    let mut cum = 0.0;
    for (j, &(radius, e)) in occupied.iter().enumerate() {
        let lo = if j == 0 {
            0.0
        } else {
            0.5 * (occupied[j - 1].0 + radius)
        };
        let hi = match occupied.get(j + 1) {
            Some(&(next, _)) => 0.5 * (radius + next),
            None => radius,
        };
        let lo = if radius == 0.0 { 0.0 } else { lo };
        if cum + e >= target {
            let t = ((target - cum) / e).clamp(0.0, 1.0);
            return lo + t * (hi - lo);
        }
        cum += e;
    }
    occupied.last().map_or(0.0, |&(r, _)| r)
}
