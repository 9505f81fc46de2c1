//! Deterministic random streams: one per work item (pixel, sample, path), derived from the user
//! seed by hashing, never from a thread, so renders are bit-identical for any thread count.

use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;

/// Distinct streams of one render, so that (say) pixel 7 of the camera and irradiance sample 7
/// never share random numbers.
#[derive(Clone, Copy, Debug)]
#[repr(u64)]
pub enum Stream {
    /// Pixel-sample positions.
    Camera = 1,
    /// Light sampling at irradiance samples.
    Irradiance = 2,
    /// Paths of the path tracer.
    Path = 3,
    /// Direct light on opaque surfaces.
    Opaque = 4,
    /// Blue-noise sample placement (per object).
    Placement = 5,
    /// Virtual point lights sampled on area and environment lights (per light).
    Vpl = 6,
    /// Light paths traced for one-bounce VPLs (per light).
    Bounce = 7,
    /// The fixed irradiance points of the many-light baselines (`mdlc`, `eelc`; per pixel
    /// sample).
    IrradiancePoints = 8,
    /// Paths of the volumetric path tracer (per pixel sample).
    Volume = 9,
    /// Rays gathering the light the surfaces trade into the irradiance samples (per sample
    /// and bounce).
    Interreflection = 10,
}

/// The generator for work item `index` of `stream` under `seed`.
pub fn rng(seed: u64, stream: Stream, index: u64) -> Pcg64Mcg {
    use sss_util::splitmix64 as mix64;
    let s = mix64(mix64(seed ^ mix64(stream as u64)) ^ index);
    Pcg64Mcg::seed_from_u64(s)
}
