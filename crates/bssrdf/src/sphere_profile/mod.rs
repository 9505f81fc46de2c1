//! A radial model's profile on a sphere: what the random walk adds to (or takes from) the
//! half-space's profile when the medium is a ball of radius R instead of a half-space.
//!
//! A planar profile cannot change with an object's size: the area of any surface within
//! chord distance r of a point is about πr², so every radial model returns the same light on
//! a 5 mm and a 40 mm sphere. Real transport does not: in a small ball less medium lies in the
//! light's way, so more of it comes back, and more of it at long range (through the ball). On
//! a 10 mm skin sphere that size effect is most of the models' deficit against volumetric path
//! tracing (`cargo xtask compare --deficit`: 0.77 / 0.84 / 0.90 of the truth per channel from
//! size alone).
//!
//! # The profile
//! On a sphere the light leaving at y from a beam entering at x (at normal incidence) depends
//! only on the chord |y − x|, and the area within chord distance r is exactly πr² for
//! r ≤ 2R (Archimedes' hat-box theorem), so the sphere's response is itself a radial profile
//! R_d^S(r) on [0, 2R] that every method integrates as it integrates any other
//! ([`crate::monte_carlo::simulate_sphere`]). [`SphereProfile`] keeps the base model's own
//! profile where the shapes agree and adds the walk's difference:
//!
//! R_d^S(r) = max(0, R_d(r) + Δ(r)) for r ≤ 2R, 0 beyond, Δ = walk_sphere − walk_half-space,
//!
//! Δ tallied per channel in [`BINS`] geometric bins of chord distance from a tenth of a
//! reduced mean free path to 2R (bin averages, interpolated linearly between bin centres),
//! both walks with the same random numbers (the same seed chunk for chunk), so that where
//! the shapes do not differ — near the entry point of a sphere many mean free paths across —
//! the difference is zero photon for photon, not the difference of two noisy tallies. For
//! R → ∞ Δ → 0 and the base model is returned. With `mc-table` as the base (the tabulated
//! fit of the same walk), R_d^S is the ball's walk, with the table's smooth near field.
//!
//! # Error and cost
//! The walks run [`PHOTONS`] photons per channel and shape (the medium's σ_s, σ_a, g and η;
//! [`crate::monte_carlo`]'s walk with analog absorption, which ends a walk when its light is
//! absorbed: 2.5–4 times sooner than weighting near albedo 1, for the same totals within
//! their noise); the bins' standard errors are kept ([`SphereProfile::delta_se`]). Measured on
//! 2 cores: 0.2 s for skin1 and 0.03 s for ketchup at R = 10 mm, 4 s for marble (albedo
//! 0.999: long walks). A material's walk is run once per process and medium and
//! radius ([`SphereDelta::cached`]). Only the sphere's shape is modelled: a real object is
//! described by one radius (see the scene key `sphere_radius`), its concave parts and thin
//! parts are not; the beam enters at normal incidence (the angular factors of the renderer
//! stay those of the material).
//!
//! ```
//! use sss_bssrdf::{Bssrdf, McTableModel, Medium, SphereProfile};
//! let skin1 = Medium::new([0.032, 0.17, 0.48], [0.74, 0.88, 1.01], 0.0, 1.3).unwrap();
//! let flat = McTableModel::new(skin1.clone());
//! let ball = SphereProfile::new(Box::new(McTableModel::new(skin1)), 10.0).unwrap();
//! // A 10 mm ball returns more red light than the half-space (less medium absorbs it).
//! assert!(ball.total_diffuse_reflectance(0) > flat.total_diffuse_reflectance(0));
//! assert_eq!(ball.rd(0, 25.0), 0.0); // no point of the ball is 20 mm or more away
//! ```

use crate::binned::{between_centres, memoized};
use crate::monte_carlo::{self, BinSpacing, WalkConfig};
use crate::radial::RadialTable;
use crate::{Bssrdf, BssrdfError, Medium, ModelKind};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// Photons per channel and shape of the walks behind [`SphereDelta`].
pub const PHOTONS: u64 = 1 << 17;

/// Chord-distance bins of Δ per channel.
pub const BINS: usize = 48;

/// The walks' seed.
const SEED: u64 = 0x5348_5045_5245;

/// The walk's difference Δ(r) = R_d^sphere(r) − R_d^half-space(r) of one medium and radius,
/// per channel, at the bins' centres (see the module documentation).
#[derive(Clone, Debug)]
pub struct SphereDelta {
    radius: f64,
    /// Per channel: bin centres (mm), Δ (1/mm²) and its standard error.
    rows: [DeltaRow; 3],
    /// Per channel: the two walks' total diffuse reflectance (ball, half-space).
    totals: [(f64, f64); 3],
}

#[derive(Clone, Debug, Default)]
struct DeltaRow {
    centres: Vec<f64>,
    delta: Vec<f64>,
    se: Vec<f64>,
}

impl DeltaRow {
    /// Δ at `r`: linear between bin centres, the end bins' values beyond them.
    fn at(&self, r: f64) -> f64 {
        between_centres(&self.centres, &self.delta, r)
    }
}

impl SphereDelta {
    /// Runs both walks for every channel of `medium` on a ball of radius `radius` (mm, finite,
    /// > 0).
    pub fn new(medium: &Medium, radius: f64) -> Result<SphereDelta, BssrdfError> {
        Self::with_photons(medium, radius, PHOTONS)
    }

    /// [`SphereDelta::new`] with `photons` per channel and shape.
    pub fn with_photons(
        medium: &Medium,
        radius: f64,
        photons: u64,
    ) -> Result<SphereDelta, BssrdfError> {
        if !(radius.is_finite() && radius > 0.0) {
            return Err(BssrdfError::InvalidArgument(format!(
                "sphere profile: the radius must be finite and > 0, got {radius} mm"
            )));
        }
        let mut rows: [DeltaRow; 3] = Default::default();
        let mut totals = [(0.0, 0.0); 3];
        for ch in 0..3 {
            let r_max = 2.0 * radius;
            let mfp = medium.reduced_mean_free_path(ch);
            let first = if mfp.is_finite() && mfp > 0.0 {
                (0.1 * mfp).min(0.01 * r_max)
            } else {
                0.01 * r_max
            };
            let mut channels = [false; 3];
            channels[ch] = true;
            let cfg = WalkConfig {
                photons: photons.max(1),
                seed: SEED,
                r_max,
                bins: BINS,
                channels,
                spacing: BinSpacing::geometric(first, r_max, BINS)?,
            };
            let flat = monte_carlo::simulate_analog(medium, &cfg, None)?;
            let ball = monte_carlo::simulate_analog(medium, &cfg, Some(radius))?;
            let row = &mut rows[ch];
            row.centres = ball.bin_centers();
            row.se = ball.se[ch]
                .iter()
                .zip(&flat.se[ch])
                .map(|(a, b)| a.hypot(*b))
                .collect();
            row.delta = ball.rd[ch]
                .iter()
                .zip(&flat.rd[ch])
                .map(|(s, p)| s - p)
                .collect();
            totals[ch] = (ball.total[ch], flat.total[ch]);
        }
        Ok(SphereDelta {
            radius,
            rows,
            totals,
        })
    }

    /// The difference of one medium and radius, computed once per process and shared (the
    /// walks take from a fraction of a second to seconds per medium).
    pub fn cached(medium: &Medium, radius: f64) -> Result<Arc<SphereDelta>, BssrdfError> {
        Self::cached_with(medium, radius, PHOTONS)
    }

    /// [`SphereDelta::cached`] with `photons` per channel and shape (kept apart per count).
    pub fn cached_with(
        medium: &Medium,
        radius: f64,
        photons: u64,
    ) -> Result<Arc<SphereDelta>, BssrdfError> {
        type Cache = Mutex<HashMap<([u64; 8], u64, u64), Arc<SphereDelta>>>;
        static CACHE: OnceLock<Cache> = OnceLock::new();
        memoized(&CACHE, (medium.bits(), radius.to_bits(), photons), || {
            SphereDelta::with_photons(medium, radius, photons)
        })
    }

    /// The ball's radius (mm).
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// Δ(r) of channel `ch` (1/mm²).
    pub fn delta(&self, ch: usize, r: f64) -> f64 {
        self.rows[ch].at(r)
    }

    /// The walks' total diffuse reflectance of channel `ch`: (ball, half-space).
    pub fn totals(&self, ch: usize) -> (f64, f64) {
        self.totals[ch]
    }
}

/// A radial model reshaped to a ball of radius R: R_d^S(r) = max(0, R_d(r) + Δ(r)) on
/// [0, 2R] (see the module documentation). Its kind and medium are the base model's; sampling,
/// densities, totals and energy radii come from a [`RadialTable`] of R_d^S.
pub struct SphereProfile {
    base: Box<dyn Bssrdf>,
    delta: Arc<SphereDelta>,
    tables: [RadialTable; 3],
}

impl std::fmt::Debug for SphereProfile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SphereProfile")
            .field("base", &self.base.kind())
            .field("radius", &self.delta.radius)
            .finish()
    }
}

impl SphereProfile {
    /// `base` reshaped to a ball of radius `radius` (mm, finite, > 0), its difference from
    /// [`SphereDelta::cached`]. The directional dipole is refused (its S is not radial).
    pub fn new(base: Box<dyn Bssrdf>, radius: f64) -> Result<SphereProfile, BssrdfError> {
        if base.kind() == ModelKind::DirectionalDipole {
            return Err(BssrdfError::InvalidArgument(
                "sphere profile: the directional dipole is not a radial profile".into(),
            ));
        }
        let delta = SphereDelta::cached(base.medium(), radius)?;
        Ok(Self::with_delta(base, delta))
    }

    /// `base` reshaped by a difference computed elsewhere (for example with more photons).
    pub fn with_delta(base: Box<dyn Bssrdf>, delta: Arc<SphereDelta>) -> SphereProfile {
        let r_max = 2.0 * delta.radius;
        let tables = std::array::from_fn(|ch| {
            // The table's grid ends at max(r_max, 10 scales): a scale of at most a tenth of
            // the diameter ends it at the diameter, so no sample lands beyond it.
            let scale = base.medium().reduced_mean_free_path(ch).min(0.1 * r_max);
            RadialTable::new(|r| reshaped(base.as_ref(), &delta, ch, r), scale, r_max)
        });
        SphereProfile {
            base,
            delta,
            tables,
        }
    }

    /// The ball's radius (mm).
    pub fn radius(&self) -> f64 {
        self.delta.radius
    }

    /// The walk's difference this profile adds.
    pub fn delta(&self) -> &SphereDelta {
        &self.delta
    }

    /// The standard errors of Δ at the bins' centres of channel `ch`, as (centre, se) pairs.
    pub fn delta_se(&self, ch: usize) -> Vec<(f64, f64)> {
        let row = &self.delta.rows[ch];
        row.centres
            .iter()
            .copied()
            .zip(row.se.iter().copied())
            .collect()
    }
}

/// R_d^S(r) = max(0, R_d(r) + Δ(r)) on [0, 2R], 0 beyond; finite.
fn reshaped(base: &dyn Bssrdf, delta: &SphereDelta, ch: usize, r: f64) -> f64 {
    let r = r.abs();
    if !(r <= 2.0 * delta.radius) {
        return 0.0;
    }
    let v = base.rd(ch, r) + delta.delta(ch, r);
    if v.is_finite() { v.max(0.0) } else { 0.0 }
}

impl Bssrdf for SphereProfile {
    fn kind(&self) -> ModelKind {
        self.base.kind()
    }

    fn medium(&self) -> &Medium {
        self.base.medium()
    }

    fn rd(&self, ch: usize, r: f64) -> f64 {
        reshaped(self.base.as_ref(), &self.delta, ch, r)
    }

    fn total_diffuse_reflectance(&self, ch: usize) -> f64 {
        self.tables[ch].total().clamp(0.0, 1.0)
    }

    fn sample_sr(&self, ch: usize, u: f64) -> f64 {
        self.tables[ch].sample(u)
    }

    fn pdf_sr(&self, ch: usize, r: f64) -> f64 {
        self.tables[ch].pdf(r)
    }

    fn radius_for_energy(&self, ch: usize, fraction: f64) -> f64 {
        self.tables[ch].radius_for_energy(fraction)
    }
}

pub mod family;

#[cfg(test)]
mod tests;
