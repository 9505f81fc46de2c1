//! The spatial bandwidth B_s of a BSSRDF model (Milaenen et al. 2019, §3.1), in cycles per mm.
//!
//! **What is transformed.** The cosine-weighted BSSRDF Ŝ = S cos θ_i as a function of the exit
//! point x_o on the tangent plane, for a fixed entry point x_i = 0 and incident direction ω_i.
//! For the separable models (standard and better dipole, photon beam diffusion, normalized
//! diffusion) Ŝ = R_d(‖x_o − x_i‖) · F_t(θ_i) cos θ_i · F_t(θ_o)/(cπ): the directional factors
//! are constants in x_o and do not change an energy fraction, so B_s is that of the radial
//! profile R_d alone (the paper's "1D diffuse reflectance spectrum", computed here on the 2-D
//! plane, see [`crate::spectrum`]). For the directional dipole Ŝ depends on ω_i and on the
//! direction of x_o − x_i: B_s is the maximum over [`DIRECTIONAL_INCIDENCE_DEG`] (the 2-D grid
//! already covers every azimuth of x_o − x_i relative to the refracted ray), as §3.1 prescribes.
//!
//! **Regularisation.** Several profiles are singular at r = 0 (normalized diffusion falls like
//! 1/r, photon beam diffusion's single-scattering term is sharply peaked); the power of a 1/r
//! profile, ∫R² 2πr dr, diverges logarithmically, so its 95 % bandwidth would grow without limit
//! as the grid is refined. Diffusion theory does not resolve structure finer than about one
//! reduced mean free path ℓ' = 1/σ'_t, so a radial profile is evaluated at √(r² + r_f²) with
//! r_f = [`SpatialOptions::floor_mfp_fraction`] · ℓ' (default ℓ'/4): the regularisation the
//! dipoles already apply to their own sources (d_r = √(r² + z_r²), Jensen et al. 2001), smooth
//! at 0 so the spectrum decays fast. The directional dipole's 2-D profile is evaluated at the
//! point moved out radially to √(r² + r_f²) and blended, with weight r²/(r² + r_f²), towards
//! its average on the circle of radius r_f, so that it stays continuous at the origin (without
//! the blend the moved profile jumps there by direction and B_s converges only to ~3 %). The
//! bandwidth of a singular profile then scales like 1/r_f; that of a profile finite at 0 (the
//! dipoles) depends on it mildly. With this, B_s converges as the grid is refined: halving the
//! step changes it by < 0.5 % for every model on the skin1, marble and ketchup presets (a test
//! checks < 1 %).
//!
//! **Grid.** Chosen from the profile's own scales, in two passes. A coarse pass samples the
//! support: step r_f / [`SpatialOptions::steps_per_floor`], half-extent the radius beyond which
//! r·R(r)² (the radial density of the power) stays below 10⁻⁹ of its peak (at least 8 r_f), at
//! most [`SpatialOptions::coarse_cells`] cells (the step grows when that binds). Its bandwidth
//! B₀ sets the final grid: step 1/(2 · [`SpatialOptions::nyquist_factor`] · B₀), so the Nyquist
//! frequency is 4 B₀ by default, and [`SpatialOptions::cells`] cells, so that B₀ spans
//! cells/(2 · nyquist_factor) = 64 frequency steps and the 95 % point is resolved to well under
//! 1 %. The profile's power beyond the final grid's half-extent 64/B₀ is negligible for every
//! model (its tail falls at least like r⁻³, the power like r⁻⁶).

use crate::BandwidthError;
use crate::spectrum::{
    DEFAULT_ENERGY_FRACTION, SpectrumGrid, check_fraction, smoothed_bandwidth_2d_cycles_per_mm,
};
use sss_bssrdf::{Bssrdf, DVec3, DirectionalDipole, Medium, ModelKind, SurfacePoint, make_model};

/// Polar angles of incidence (degrees from the normal) over which the directional dipole's B_s
/// is maximised.
pub const DIRECTIONAL_INCIDENCE_DEG: [f64; 5] = [0.0, 30.0, 50.0, 70.0, 85.0];

/// How B_s is computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpatialOptions {
    /// Energy fraction of the discrete power spectrum below B_s, in (0, 1). Default 0.95
    /// (Milaenen et al. 2019, §5).
    pub energy_fraction: f64,
    /// The regularisation radius r_f as a fraction of the reduced mean free path
    /// ℓ' = 1/σ'_t: profiles are evaluated at √(r² + r_f²) (see the module docs). Default 0.25.
    /// Must be > 0.
    pub floor_mfp_fraction: f64,
    /// Coarse-grid samples per regularisation radius r_f. Default 4. Must be ≥ 1.
    pub steps_per_floor: f64,
    /// Cells per side of the coarse pass over the profile's support. Default 512.
    pub coarse_cells: usize,
    /// Cells per side of the final grid. Default 512.
    pub cells: usize,
    /// The final grid's Nyquist frequency as a multiple of the coarse bandwidth. Default 4.
    pub nyquist_factor: f64,
}

impl Default for SpatialOptions {
    fn default() -> Self {
        SpatialOptions {
            energy_fraction: DEFAULT_ENERGY_FRACTION,
            floor_mfp_fraction: 0.25,
            steps_per_floor: 4.0,
            coarse_cells: 512,
            cells: 512,
            nyquist_factor: 4.0,
        }
    }
}

impl SpatialOptions {
    fn check(&self) -> Result<(), BandwidthError> {
        check_fraction(self.energy_fraction)?;
        if !(self.floor_mfp_fraction > 0.0) || !self.floor_mfp_fraction.is_finite() {
            return Err(BandwidthError::InvalidArgument(format!(
                "floor_mfp_fraction {}: must be finite and > 0",
                self.floor_mfp_fraction
            )));
        }
        if !(self.steps_per_floor >= 1.0) || !self.steps_per_floor.is_finite() {
            return Err(BandwidthError::InvalidArgument(format!(
                "steps_per_floor {}: must be finite and >= 1",
                self.steps_per_floor
            )));
        }
        for (name, v) in [("coarse_cells", self.coarse_cells), ("cells", self.cells)] {
            if !(64..=crate::spectrum::MAX_CELLS).contains(&v) {
                return Err(BandwidthError::InvalidArgument(format!(
                    "{name} {v}: must be in 64..={}",
                    crate::spectrum::MAX_CELLS
                )));
            }
        }
        if !(self.nyquist_factor >= 1.0) || !self.nyquist_factor.is_finite() {
            return Err(BandwidthError::InvalidArgument(format!(
                "nyquist_factor {}: must be finite and >= 1",
                self.nyquist_factor
            )));
        }
        Ok(())
    }
}

/// The floor radius r_f (mm) of channel `ch` of `medium`: `fraction` · 1/σ'_t.
fn floor_radius(medium: &Medium, ch: usize, fraction: f64) -> f64 {
    let sigma_tp = medium.sigma_t_reduced(ch);
    // σ'_t = σ_a + σ_s(1 − g) > 0 for every valid medium (σ_t > 0, |g| < 1).
    fraction / sigma_tp.max(f64::MIN_POSITIVE)
}

/// The grid for a radial profile `rd` regularised at radius `r_floor`, i.e. evaluated at
/// √(r² + `r_floor`²) (see the module docs):
/// a coarse pass on the profile's support estimates B₀, then the returned grid has step
/// 1/(2 · [`SpatialOptions::nyquist_factor`] · B₀) and [`SpatialOptions::cells`] cells. A
/// profile that is zero everywhere gets the coarse grid.
pub fn grid_for_profile(
    rd: impl Fn(f64) -> f64,
    r_floor: f64,
    opts: &SpatialOptions,
) -> Result<SpectrumGrid, BandwidthError> {
    opts.check()?;
    if !(r_floor > 0.0) || !r_floor.is_finite() {
        return Err(BandwidthError::InvalidArgument(format!(
            "floor radius {r_floor} mm: must be finite and > 0"
        )));
    }
    let rd_floored = |r: f64| rd(r.hypot(r_floor));
    let coarse = support_grid(&rd_floored, r_floor, opts)?;
    let b0 =
        crate::spectrum::radial_bandwidth_cycles_per_mm(rd_floored, &coarse, opts.energy_fraction)?;
    grid_for_bandwidth(b0, opts).map(|g| g.unwrap_or(coarse))
}

/// The fine grid for a bandwidth estimate `b0` (cycles per mm), or `None` when `b0` is 0.
fn grid_for_bandwidth(
    b0: f64,
    opts: &SpatialOptions,
) -> Result<Option<SpectrumGrid>, BandwidthError> {
    if !(b0 > 0.0) || !b0.is_finite() {
        return Ok(None);
    }
    SpectrumGrid::new(1.0 / (2.0 * opts.nyquist_factor * b0), opts.cells).map(Some)
}

/// The coarse grid: step r_f / steps_per_floor, half-extent where r·R(r)² falls below 10⁻⁹ of
/// its peak (at least 8 r_f), at most `coarse_cells` cells (the step grows when that binds).
fn support_grid(
    rd_floored: &impl Fn(f64) -> f64,
    r_floor: f64,
    opts: &SpatialOptions,
) -> Result<SpectrumGrid, BandwidthError> {
    let density = |r: f64| {
        let v = rd_floored(r);
        if v.is_finite() { r * v * v } else { 0.0 }
    };
    // Geometric scan from r_f out to 10⁵ r_f.
    let ratio = 1.05f64;
    let steps = (1e5f64.ln() / ratio.ln()).ceil() as usize;
    let scan: Vec<(f64, f64)> = (0..steps)
        .map(|i| {
            let r = r_floor * ratio.powi(i as i32);
            (r, density(r))
        })
        .collect();
    let peak = scan.iter().fold(0.0f64, |m, &(_, d)| m.max(d));
    let support = scan
        .iter()
        .filter(|&&(_, d)| d > 1e-9 * peak)
        .fold(r_floor, |m, &(r, _)| m.max(r));
    let half_extent = support.max(8.0 * r_floor);
    let mut step = r_floor / opts.steps_per_floor;
    let mut cells = (2.0 * half_extent / step).ceil() as usize;
    if cells > opts.coarse_cells {
        cells = opts.coarse_cells;
        step = 2.0 * half_extent / cells as f64;
    }
    SpectrumGrid::new(step, cells.max(64))
}

/// B_s (cycles per mm) of a radial profile `rd(r_mm)` evaluated at √(r² + `r_floor_mm`²), on the
/// grid [`grid_for_profile`] chooses. Use it for profiles that are not models of `sss-bssrdf`.
pub fn profile_spatial_bandwidth_cycles_per_mm(
    rd: impl Fn(f64) -> f64,
    r_floor_mm: f64,
    opts: &SpatialOptions,
) -> Result<f64, BandwidthError> {
    let grid = grid_for_profile(&rd, r_floor_mm, opts)?;
    crate::spectrum::radial_bandwidth_cycles_per_mm(
        |r| rd(r.hypot(r_floor_mm)),
        &grid,
        opts.energy_fraction,
    )
}

/// The grid [`spatial_bandwidth_cycles_per_mm`] uses for channel `ch` of `model`: that of
/// [`grid_for_profile`] for the radial models; for the directional dipole the coarse pass takes
/// the maximum over [`DIRECTIONAL_INCIDENCE_DEG`] of the 2-D profiles.
pub fn model_grid(
    model: &dyn Bssrdf,
    ch: usize,
    opts: &SpatialOptions,
) -> Result<SpectrumGrid, BandwidthError> {
    check_channel(ch)?;
    let r_floor = floor_radius(model.medium(), ch, opts.floor_mfp_fraction);
    if model.kind() != ModelKind::DirectionalDipole {
        return grid_for_profile(|r| model.rd(ch, r), r_floor, opts);
    }
    opts.check()?;
    let coarse = support_grid(&|r: f64| model.rd(ch, r.hypot(r_floor)), r_floor, opts)?;
    let b0 = spatial_bandwidth_on_grid(model, ch, &coarse, opts)?;
    grid_for_bandwidth(b0, opts).map(|g| g.unwrap_or(coarse))
}

fn check_channel(ch: usize) -> Result<(), BandwidthError> {
    if ch > 2 {
        return Err(BandwidthError::InvalidArgument(format!(
            "channel {ch}: must be 0, 1 or 2"
        )));
    }
    Ok(())
}

/// The range of σ'_t (1/mm) in which [`spatial_bandwidth_cycles_per_mm`] evaluates the given
/// model directly; outside it, it uses the scaling law (see there).
pub const DIRECT_SIGMA_T_REDUCED: (f64, f64) = (1e-3, 1e3);

/// B_s (cycles per mm) of channel `ch` (0, 1, 2) of `model`: see the module docs for what is
/// transformed, the regularisation and the grid. 0 for a channel whose profile is 0 (no
/// scattering, or a profile that underflows).
///
/// **Extreme coefficients.** The diffusion models are functions of σ·r, so scaling σ_a and σ_s
/// by c scales B_s by c exactly (a test checks it to 10⁻³). When σ'_t of the channel lies
/// outside [`DIRECT_SIGMA_T_REDUCED`], where profile values can overflow or underflow f64, B_s
/// is computed on the built-in model of the same [`ModelKind`] (`sss_bssrdf::make_model`) for
/// the channel's medium scaled to σ'_t = 1, and multiplied by σ'_t. So the result is finite
/// for every valid medium, at the price that a custom model (e.g. normalized diffusion with a
/// non-default fit) is replaced by the built-in one there.
pub fn spatial_bandwidth_cycles_per_mm(
    model: &dyn Bssrdf,
    ch: usize,
    opts: &SpatialOptions,
) -> Result<f64, BandwidthError> {
    check_channel(ch)?;
    let medium = model.medium();
    let scale = medium.sigma_t_reduced(ch);
    let (lo, hi) = DIRECT_SIGMA_T_REDUCED;
    if !(scale >= lo && scale <= hi) && scale > 0.0 && scale.is_finite() {
        let sigma_a = medium.sigma_a()[ch] / scale;
        let sigma_s = medium.sigma_s()[ch] / scale;
        let normalised = Medium::new([sigma_a; 3], [sigma_s; 3], medium.g(), medium.eta())
            .map_err(|e| BandwidthError::InvalidArgument(format!("normalised medium: {e}")))?;
        let unit = make_model(model.kind(), &normalised);
        let grid = model_grid(unit.as_ref(), 0, opts)?;
        let b = spatial_bandwidth_on_grid(unit.as_ref(), 0, &grid, opts)? * scale;
        return if b.is_finite() {
            Ok(b)
        } else {
            Err(BandwidthError::InvalidArgument(format!(
                "B_s overflows f64 for σ'_t = {scale} 1/mm"
            )))
        };
    }
    let grid = model_grid(model, ch, opts)?;
    spatial_bandwidth_on_grid(model, ch, &grid, opts)
}

/// B_s (cycles per mm) of channel `ch` of `model` on a given `grid` (same definition as
/// [`spatial_bandwidth_cycles_per_mm`], which picks the grid itself); for convergence studies.
pub fn spatial_bandwidth_on_grid(
    model: &dyn Bssrdf,
    ch: usize,
    grid: &SpectrumGrid,
    opts: &SpatialOptions,
) -> Result<f64, BandwidthError> {
    opts.check()?;
    check_channel(ch)?;
    let medium = model.medium();
    let r_floor = floor_radius(medium, ch, opts.floor_mfp_fraction);
    if model.kind() != ModelKind::DirectionalDipole {
        return crate::spectrum::radial_bandwidth_cycles_per_mm(
            |r| model.rd(ch, r.hypot(r_floor)),
            grid,
            opts.energy_fraction,
        );
    }
    // The directional dipole: the maximum over incident angles of the 2-D profile on the plane.
    let dd = DirectionalDipole::new(medium.clone());
    let n = DVec3::Z;
    let xi = SurfacePoint { p: DVec3::ZERO, n };
    let mut best = 0.0f64;
    for deg in DIRECTIONAL_INCIDENCE_DEG {
        let t = deg.to_radians();
        let wi = DVec3::new(t.sin(), 0.0, t.cos());
        let eval = |x: f64, y: f64| {
            let xo = SurfacePoint {
                p: DVec3::new(x, y, 0.0),
                n,
            };
            dd.transport(ch, &xi, wi, &xo)
        };
        // The circle of radius r_f, averaged over 64 azimuths: the value at the origin.
        let ring = (0..64)
            .map(|i| {
                let phi = std::f64::consts::TAU * (i as f64 + 0.5) / 64.0;
                eval(r_floor * phi.cos(), r_floor * phi.sin())
            })
            .sum::<f64>()
            / 64.0;
        let profile = |x: f64, y: f64| {
            // Moved out radially to √(r² + r_f²) like the radial profiles, and blended with
            // weight r²/(r² + r_f²) towards the ring average, so it is continuous at 0.
            let r2 = x * x + y * y;
            let rr = r2 + r_floor * r_floor;
            if r2 == 0.0 {
                return ring;
            }
            let s = (rr / r2).sqrt();
            let w = r2 / rr;
            w * eval(x * s, y * s) + (1.0 - w) * ring
        };
        best = best.max(smoothed_bandwidth_2d_cycles_per_mm(
            profile,
            grid,
            opts.energy_fraction,
            0.0,
        )?);
    }
    Ok(best)
}

/// B_s of the three channels of `model` (cycles per mm).
pub fn spatial_bandwidths_cycles_per_mm(
    model: &dyn Bssrdf,
    opts: &SpatialOptions,
) -> Result<[f64; 3], BandwidthError> {
    Ok([
        spatial_bandwidth_cycles_per_mm(model, 0, opts)?,
        spatial_bandwidth_cycles_per_mm(model, 1, opts)?,
        spatial_bandwidth_cycles_per_mm(model, 2, opts)?,
    ])
}
