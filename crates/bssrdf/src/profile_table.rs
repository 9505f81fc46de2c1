//! One table type for tabulated radial profiles ([`ProfileTable`]), as pbrt 3rd ed. keeps one
//! `BSSRDFTable` (§11.4.2) whatever fills it: rows of albedos, columns of optical radii, the
//! values 2πr R_d¹(r) of a unit-extinction medium, each row's running integral and total
//! (its effective albedo), read by Catmull-Rom interpolation in albedo and radius.
//!
//! Two codes fill it: photon beam diffusion's closed forms
//! ([`crate::photon_beam_diffusion::PbdTable`], pbrt §15.5.5) and the crate's own tabulated
//! random walk ([`crate::mc_table::McTable`]). Each is a thin wrapper that builds the table and
//! dereferences to it, so the evaluation is written once.

use crate::catmull_rom::{
    apply_weights, catmull_rom_weights, integrate_catmull_rom, interpolate_catmull_rom,
};
use crate::spline_row::KnotIndex;

/// Albedo rows × optical-radius columns of T(ρ, r) = 2πr R_d¹(r), with each row's running
/// integral and total (see the module documentation).
#[derive(Clone, Debug)]
pub struct ProfileTable {
    g: f64,
    eta: f64,
    rho_samples: Vec<f64>,
    radius_samples: Vec<f64>,
    /// Row-major rows × radii values of T.
    profile: Vec<f64>,
    /// Row-major running integrals of the profile splines.
    profile_cdf: Vec<f64>,
    /// ρ_eff per albedo row: the integral of the row's spline.
    rho_eff: Vec<f64>,
    /// Constant-time interval lookup over the radius nodes.
    index: KnotIndex,
}

impl ProfileTable {
    /// The table of `profile` (row-major, one row per entry of `rho_samples`, one column per
    /// entry of `radius_samples`, which must increase): each row's running integral and total
    /// are computed here ([`integrate_catmull_rom`]), so they describe exactly the spline that
    /// is interpolated and sampled. `None` when the radii do not increase or the lengths do
    /// not match.
    pub fn new(
        g: f64,
        eta: f64,
        rho_samples: Vec<f64>,
        radius_samples: Vec<f64>,
        profile: Vec<f64>,
    ) -> Option<ProfileTable> {
        let n = radius_samples.len();
        if n == 0 || profile.len() != rho_samples.len() * n {
            return None;
        }
        let index = KnotIndex::new(&radius_samples)?;
        let mut profile_cdf = Vec::with_capacity(profile.len());
        let mut rho_eff = Vec::with_capacity(rho_samples.len());
        for row in profile.chunks_exact(n) {
            let (total, cdf) = integrate_catmull_rom(&radius_samples, row);
            profile_cdf.extend(cdf);
            rho_eff.push(total);
        }
        Some(ProfileTable {
            g,
            eta,
            rho_samples,
            radius_samples,
            profile,
            profile_cdf,
            rho_eff,
            index,
        })
    }

    /// Henyey-Greenstein anisotropy of the table.
    pub fn g(&self) -> f64 {
        self.g
    }

    /// Relative index of refraction of the table.
    pub fn eta(&self) -> f64 {
        self.eta
    }

    /// The albedo rows ρ_i.
    pub fn rho_samples(&self) -> &[f64] {
        &self.rho_samples
    }

    /// The optical radius nodes r_j (mean free paths 1/σ_t).
    pub fn radius_samples(&self) -> &[f64] {
        &self.radius_samples
    }

    /// Largest tabulated optical radius; the profile is 0 beyond it.
    pub fn max_optical_radius(&self) -> f64 {
        self.radius_samples[self.radius_samples.len() - 1]
    }

    /// The value T(ρ_i, r_j) = 2π r_j R_d¹(r_j) at albedo row `i`, radius column `j`.
    pub fn profile(&self, i: usize, j: usize) -> f64 {
        self.profile[i * self.radius_samples.len() + j]
    }

    /// Row-major rows × radii array of all profile values.
    pub fn profile_values(&self) -> &[f64] {
        &self.profile
    }

    /// Row-major rows × radii running integrals of the profile splines (each row from
    /// [`integrate_catmull_rom`]).
    pub fn profile_cdf_values(&self) -> &[f64] {
        &self.profile_cdf
    }

    /// The effective albedo ρ_eff of every albedo row (the integral of the row's spline).
    pub fn rho_eff_samples(&self) -> &[f64] {
        &self.rho_eff
    }

    /// The interval lookup over the radius nodes, for blending rows ([`crate::spline_row`]).
    pub(crate) fn index(&self) -> &KnotIndex {
        &self.index
    }

    /// Spline-interpolated effective albedo ρ_eff(ρ) (pbrt Eq. 11.11, interpolated as
    /// `TabulatedBSSRDF` does), unclamped; 0 outside [0, 1].
    pub(crate) fn effective_albedo_raw(&self, rho: f64) -> f64 {
        match catmull_rom_weights(&self.rho_samples, rho) {
            Some((offset, w)) => apply_weights(offset, &w, |i| self.rho_eff[i]),
            None => 0.0,
        }
    }

    /// The total diffuse reflectance (effective albedo) of single-scattering albedo `rho`,
    /// Catmull-Rom interpolated over the rows' ρ_eff and clamped to [0, 1]; 0 for `rho`
    /// outside [0, 1].
    pub fn effective_albedo(&self, rho: f64) -> f64 {
        let v = self.effective_albedo_raw(rho);
        if v.is_finite() {
            v.clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    /// Tensor-product spline interpolation of T at albedo `rho` and optical radius
    /// `r_optical` (pbrt §11.4.2 `TabulatedBSSRDF::Sr`), or `None` outside the table. May be
    /// slightly negative where a spline overshoots.
    pub fn interpolate_profile(&self, rho: f64, r_optical: f64) -> Option<f64> {
        let (ro, rw) = catmull_rom_weights(&self.rho_samples, rho)?;
        let n = self.radius_samples.len();
        let (co, cw) = catmull_rom_weights(&self.radius_samples, r_optical)?;
        Some(apply_weights(ro, &rw, |i| {
            apply_weights(co, &cw, |j| self.profile[i * n + j])
        }))
    }

    /// The spline of albedo row `i` at optical radius `x` (`None` outside the knots).
    pub fn row_spline(&self, i: usize, x: f64) -> Option<f64> {
        let n = self.radius_samples.len();
        interpolate_catmull_rom(&self.radius_samples, &self.profile[i * n..(i + 1) * n], x)
    }
}
