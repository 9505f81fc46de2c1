//! From the BSSRDF's bandwidth at the surface to the screen: the transport operators of
//! Milaenen et al. 2019, Eq. 3 (after Durand et al. 2005 and Bagher et al. 2012), the angular
//! bandwidth at the sensor B_a (Eq. 4) and the per-pixel sampling rate s_p (Eq. 5).
//!
//! **Units.** Spatial bandwidths in cycles per mm, angular ones in cycles per radian, curvature
//! k in 1/mm, distance d in mm. Any other length unit works if it is used for all of them
//! (k and d in the unit whose inverse measures B_s).
//!
//! **Operators** on the bandwidth vector [B_s, B_θ]ᵀ (Eq. 3):
//! C_k = [[1, k], [0, 1]] (curvature: the spatial bandwidth picks up k × the angular one),
//! P_x = [[1/cos θ_o, 0], [0, 1]] (foreshortening towards the viewer), and
//! T_d = [[1, 0], [d, 1]] (free-space travel over d: the angular bandwidth picks up d × the
//! spatial one); [B_p, B_a]ᵀ = T_d P_x C_k [B_s, B_θ]ᵀ, so B_a = B_θ + d (B_s + k B_θ)/cos θ_o
//! (Eq. 4). The signs of the shears differ between sources (see `../shared/docs/wave2.md`
//! F1.2); a bandwidth is an extent, so this crate uses the **conservative** form
//! B_a = B_θ + d (B_s + |k| B_θ) / max(|cos θ_o|, c_min), the triangle inequality on |Ω|, with
//! c_min = [`MIN_COS_THETA_O`] unless a caller picks another.
//!
//! **Edge cases** (all finite):
//! - grazing view (cos θ_o → 0): 1/cos θ_o is capped at 1/c_min = 1000, so B_a ≤ B_θ +
//!   1000 d (B_s + |k| B_θ); the pixel then gets a very high rate and is shaded on its own;
//! - cos θ_o < 0 (a back-facing sample, e.g. from normal interpolation): |cos θ_o| is used;
//! - k = 0 (a plane): B_a = B_θ + d B_s / cos θ_o; negative k (concave) counts as |k|, since a
//!   shear of either sign widens the spectrum's extent;
//! - d → 0: B_a → B_θ (the light field at the surface itself).
//!
//! **Sampling rate** (Eq. 5): s_p = 2 B_a · max(f_x/W, f_y/H), with the fields of view f in
//! radians, i.e. twice the bandwidth (Nyquist) times the angle one pixel subtends: samples per
//! pixel. A pixel cluster may span P = ρ/s_p pixels (Eq. 6).

use crate::BandwidthError;

/// Default lower clamp of |cos θ_o| in Eq. 4 (1/cos ≤ 1000, i.e. within 0.057° of grazing).
pub const MIN_COS_THETA_O: f64 = 1e-3;

/// A 2 × 2 operator on [B_s, B_θ]ᵀ, row-major.
pub type Operator = [[f64; 2]; 2];

/// A spatial–angular bandwidth vector [B_s, B_θ]ᵀ.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BandwidthVector {
    /// Spatial bandwidth B_s (cycles per mm).
    pub spatial_cycles_per_mm: f64,
    /// Angular bandwidth B_θ (cycles per radian).
    pub angular_cycles_per_radian: f64,
}

impl BandwidthVector {
    /// Applies `op`: [op₀₀ B_s + op₀₁ B_θ, op₁₀ B_s + op₁₁ B_θ].
    pub fn apply(self, op: &Operator) -> BandwidthVector {
        let (s, a) = (self.spatial_cycles_per_mm, self.angular_cycles_per_radian);
        BandwidthVector {
            spatial_cycles_per_mm: op[0][0] * s + op[0][1] * a,
            angular_cycles_per_radian: op[1][0] * s + op[1][1] * a,
        }
    }
}

/// C_k (Eq. 3): curvature `k_per_mm` shears spatial frequency by k × angular.
pub fn curvature_operator(k_per_mm: f64) -> Operator {
    [[1.0, k_per_mm], [0.0, 1.0]]
}

/// P_x (Eq. 3): foreshortening, spatial bandwidth divided by `cos_theta_o` (unclamped; see
/// [`screen_angular_bandwidth`] for the clamped use).
pub fn projection_operator(cos_theta_o: f64) -> Operator {
    [[1.0 / cos_theta_o, 0.0], [0.0, 1.0]]
}

/// T_d (Eq. 3): travel over `d_mm` shears angular frequency by d × spatial.
pub fn travel_operator(d_mm: f64) -> Operator {
    [[1.0, 0.0], [d_mm, 1.0]]
}

/// Where a shade point sits relative to the camera.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadeGeometry {
    /// Surface curvature k at the point (1/mm); the sign is ignored (see the module docs).
    pub curvature_per_mm: f64,
    /// Distance from the point to the camera (mm), ≥ 0.
    pub distance_mm: f64,
    /// Cosine between the surface normal and the direction to the camera.
    pub cos_theta_o: f64,
}

fn check_bandwidth(b: BandwidthVector) -> Result<(), BandwidthError> {
    let (s, a) = (b.spatial_cycles_per_mm, b.angular_cycles_per_radian);
    if !(s >= 0.0) || !s.is_finite() || !(a >= 0.0) || !a.is_finite() {
        return Err(BandwidthError::InvalidArgument(format!(
            "bandwidths ({s} cycles/mm, {a} cycles/rad): must be finite and >= 0"
        )));
    }
    Ok(())
}

/// B_a (cycles per radian at the camera), the conservative Eq. 4:
/// B_θ + d (B_s + |k| B_θ) / max(|cos θ_o|, `min_cos`). Errors on negative or non-finite
/// bandwidths, distance or `min_cos` outside (0, 1], non-finite curvature or a NaN cosine.
pub fn screen_angular_bandwidth(
    b: BandwidthVector,
    geometry: &ShadeGeometry,
    min_cos: f64,
) -> Result<f64, BandwidthError> {
    check_bandwidth(b)?;
    let ShadeGeometry {
        curvature_per_mm: k,
        distance_mm: d,
        cos_theta_o: c,
    } = *geometry;
    if !(d >= 0.0) || !d.is_finite() {
        return Err(BandwidthError::InvalidArgument(format!(
            "distance {d} mm: must be finite and >= 0"
        )));
    }
    if !k.is_finite() {
        return Err(BandwidthError::InvalidArgument(format!(
            "curvature {k} 1/mm: must be finite"
        )));
    }
    if c.is_nan() {
        return Err(BandwidthError::InvalidArgument(
            "cos θ_o is NaN".to_string(),
        ));
    }
    if !(min_cos > 0.0 && min_cos <= 1.0) {
        return Err(BandwidthError::InvalidArgument(format!(
            "min_cos {min_cos}: must be in (0, 1]"
        )));
    }
    let cos = c.abs().clamp(min_cos, 1.0);
    let ba = b.angular_cycles_per_radian
        + d * (b.spatial_cycles_per_mm + k.abs() * b.angular_cycles_per_radian) / cos;
    // Overflow to ∞ would need bandwidths or distances near f64::MAX; report it.
    if !ba.is_finite() {
        return Err(BandwidthError::InvalidArgument(format!(
            "B_a overflows for {b:?} at {geometry:?}"
        )));
    }
    Ok(ba)
}

/// The image's angular footprint: fields of view (radians) and resolution (pixels).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelFootprint {
    /// Horizontal field of view f_x (radians).
    pub fov_x_rad: f64,
    /// Vertical field of view f_y (radians).
    pub fov_y_rad: f64,
    /// Width W (pixels).
    pub width_px: u32,
    /// Height H (pixels).
    pub height_px: u32,
}

impl PixelFootprint {
    /// max(f_x/W, f_y/H): radians per pixel. Errors unless both fields of view are in (0, 2π)
    /// and both sizes > 0.
    pub fn radians_per_pixel(&self) -> Result<f64, BandwidthError> {
        for (name, f) in [("fov_x", self.fov_x_rad), ("fov_y", self.fov_y_rad)] {
            if !(f > 0.0 && f < std::f64::consts::TAU) {
                return Err(BandwidthError::InvalidArgument(format!(
                    "{name} {f} rad: must be in (0, 2π)"
                )));
            }
        }
        if self.width_px == 0 || self.height_px == 0 {
            return Err(BandwidthError::InvalidArgument(format!(
                "image {}×{}: both sizes must be > 0",
                self.width_px, self.height_px
            )));
        }
        Ok((self.fov_x_rad / f64::from(self.width_px))
            .max(self.fov_y_rad / f64::from(self.height_px)))
    }
}

/// s_p (samples per pixel) from B_a (cycles per radian), Eq. 5: 2 B_a max(f_x/W, f_y/H).
pub fn sampling_rate_per_pixel(
    b_a_cycles_per_radian: f64,
    footprint: &PixelFootprint,
) -> Result<f64, BandwidthError> {
    if !(b_a_cycles_per_radian >= 0.0) || !b_a_cycles_per_radian.is_finite() {
        return Err(BandwidthError::InvalidArgument(format!(
            "B_a {b_a_cycles_per_radian} cycles/rad: must be finite and >= 0"
        )));
    }
    Ok(2.0 * b_a_cycles_per_radian * footprint.radians_per_pixel()?)
}
