//! The per-material cache: B_s per channel and the B_θ(θ_o) table, computed once from a model
//! (the paper's "Fourier precomputation", Table 1) and cheap to query per pixel.

use crate::BandwidthError;
use crate::angular::{AngularOptions, AngularTable};
use crate::spatial::{SpatialOptions, spatial_bandwidths_cycles_per_mm};
use crate::transport::{
    BandwidthVector, MIN_COS_THETA_O, PixelFootprint, ShadeGeometry, sampling_rate_per_pixel,
    screen_angular_bandwidth,
};
use sss_bssrdf::{Bssrdf, ModelKind};

/// Bandwidths of one material: what Eq. 4–5 need per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialBandwidth {
    kind: ModelKind,
    spatial: [f64; 3],
    angular: AngularTable,
    min_cos: f64,
}

impl MaterialBandwidth {
    /// Computes B_s of the three channels of `model` and the B_θ table of its η with the
    /// default options (about 0.1–0.3 s for a radial model, 1–2 s for the directional dipole
    /// on one core).
    pub fn new(model: &dyn Bssrdf) -> Result<Self, BandwidthError> {
        Self::with_options(
            model,
            &SpatialOptions::default(),
            &AngularOptions::default(),
            MIN_COS_THETA_O,
        )
    }

    /// As [`MaterialBandwidth::new`] with explicit options and the clamp `min_cos` of |cos θ_o|
    /// in (0, 1] used by Eq. 4.
    pub fn with_options(
        model: &dyn Bssrdf,
        spatial: &SpatialOptions,
        angular: &AngularOptions,
        min_cos: f64,
    ) -> Result<Self, BandwidthError> {
        if !(min_cos > 0.0 && min_cos <= 1.0) {
            return Err(BandwidthError::InvalidArgument(format!(
                "min_cos {min_cos}: must be in (0, 1]"
            )));
        }
        Ok(MaterialBandwidth {
            kind: model.kind(),
            spatial: spatial_bandwidths_cycles_per_mm(model, spatial)?,
            angular: AngularTable::new(model.medium().eta(), angular)?,
            min_cos,
        })
    }

    /// From precomputed parts (e.g. a cache on disk, or a test).
    pub fn from_parts(
        kind: ModelKind,
        spatial_cycles_per_mm: [f64; 3],
        angular: AngularTable,
        min_cos: f64,
    ) -> Result<Self, BandwidthError> {
        if spatial_cycles_per_mm
            .iter()
            .any(|b| !(*b >= 0.0) || !b.is_finite())
        {
            return Err(BandwidthError::InvalidArgument(format!(
                "spatial bandwidths {spatial_cycles_per_mm:?}: must be finite and >= 0"
            )));
        }
        if !(min_cos > 0.0 && min_cos <= 1.0) {
            return Err(BandwidthError::InvalidArgument(format!(
                "min_cos {min_cos}: must be in (0, 1]"
            )));
        }
        Ok(MaterialBandwidth {
            kind,
            spatial: spatial_cycles_per_mm,
            angular,
            min_cos,
        })
    }

    /// The model the bandwidths were computed for.
    pub fn kind(&self) -> ModelKind {
        self.kind
    }

    /// B_s per channel (cycles per mm).
    pub fn spatial_cycles_per_mm(&self) -> [f64; 3] {
        self.spatial
    }

    /// The largest B_s over the channels (cycles per mm): the conservative per-pixel value.
    pub fn max_spatial_cycles_per_mm(&self) -> f64 {
        self.spatial.iter().fold(0.0f64, |m, &b| m.max(b))
    }

    /// The B_θ(θ_o) table.
    pub fn angular(&self) -> &AngularTable {
        &self.angular
    }

    /// The clamp of |cos θ_o| used by Eq. 4.
    pub fn min_cos(&self) -> f64 {
        self.min_cos
    }

    /// [B_s, B_θ(θ_o)] at outgoing cosine `cos_theta_o`, with B_s the maximum over channels.
    pub fn bandwidth_at(&self, cos_theta_o: f64) -> BandwidthVector {
        BandwidthVector {
            spatial_cycles_per_mm: self.max_spatial_cycles_per_mm(),
            angular_cycles_per_radian: self.angular.cycles_per_radian_at_cos(cos_theta_o),
        }
    }

    /// B_a (cycles per radian) at a shade point (Eq. 4, conservative form; see
    /// [`crate::transport`]).
    pub fn screen_angular_bandwidth(
        &self,
        geometry: &ShadeGeometry,
    ) -> Result<f64, BandwidthError> {
        screen_angular_bandwidth(
            self.bandwidth_at(geometry.cos_theta_o),
            geometry,
            self.min_cos,
        )
    }

    /// s_p (samples per pixel) at a shade point (Eq. 4–5).
    pub fn sampling_rate_per_pixel(
        &self,
        geometry: &ShadeGeometry,
        footprint: &PixelFootprint,
    ) -> Result<f64, BandwidthError> {
        sampling_rate_per_pixel(self.screen_angular_bandwidth(geometry)?, footprint)
    }
}
