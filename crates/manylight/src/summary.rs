//! Frame-level counts of the per-pixel outcomes, so a renderer can report how many pixels hit
//! each cap or hazard (the number of pixels that hit a cap).

use crate::estimator::{PixelEstimate, Status};

/// Sums over the pixels of a frame. Add pixels in any order; [`Summary::merge`] combines the
/// partial sums of threads (all fields are integers, so the result does not depend on the
/// order).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Summary {
    /// Pixels estimated.
    pub pixels: u64,
    /// Pixels that met ΔI < εI.
    pub converged: u64,
    /// Pixels that stopped at the absolute floor on ΔI (`Settings::floor`).
    pub floor: u64,
    /// Pixels that stopped at the triplet cap.
    pub triplet_cap: u64,
    /// Pixels in which the split cap refused at least one split.
    pub split_cap: u64,
    /// Pixels that stopped with every triplet frozen.
    pub exhausted: u64,
    /// Pixels declared 0 (all samples 0 after `min_triplets`).
    pub zero: u64,
    /// Pixels exactly 0 by the bound.
    pub exact: u64,
    /// Triplets at the end, summed.
    pub triplets: u64,
    /// Triangle splits, summed.
    pub splits: u64,
    /// Samples, summed.
    pub samples: u64,
    /// Samples whose G was clamped, summed.
    pub g_clamped: u64,
    /// Live zero-variance triplets at the end, summed.
    pub zero_variance: u64,
}

impl Summary {
    /// Counts one pixel.
    pub fn add(&mut self, p: &PixelEstimate) {
        self.pixels += 1;
        match p.status {
            Status::Converged => self.converged += 1,
            Status::Floor => self.floor += 1,
            Status::TripletCap => self.triplet_cap += 1,
            Status::Exhausted => self.exhausted += 1,
            Status::Zero => self.zero += 1,
            Status::Exact => self.exact += 1,
        }
        self.split_cap += u64::from(p.split_cap_hits > 0);
        self.triplets += p.triplets as u64;
        self.splits += p.splits as u64;
        self.samples += p.samples;
        self.g_clamped += p.g_clamped;
        self.zero_variance += p.zero_variance as u64;
    }

    /// Adds another partial summary.
    pub fn merge(&mut self, o: &Summary) {
        self.pixels += o.pixels;
        self.converged += o.converged;
        self.floor += o.floor;
        self.triplet_cap += o.triplet_cap;
        self.split_cap += o.split_cap;
        self.exhausted += o.exhausted;
        self.zero += o.zero;
        self.exact += o.exact;
        self.triplets += o.triplets;
        self.splits += o.splits;
        self.samples += o.samples;
        self.g_clamped += o.g_clamped;
        self.zero_variance += o.zero_variance;
    }

    /// Mean triplets per pixel (0 for no pixels).
    pub fn mean_triplets(&self) -> f64 {
        if self.pixels == 0 {
            0.0
        } else {
            self.triplets as f64 / self.pixels as f64
        }
    }
}
