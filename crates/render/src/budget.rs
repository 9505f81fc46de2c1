//! Memory estimated before it is allocated: a render's largest allocations grow with user
//! input (resolution × pixel samples), so [`check_frame`] estimates them from the scene alone
//! and refuses, with one clear error naming the input, the bytes and the budget, a frame that
//! would not fit — instead of an allocation failure that aborts the process.
//!
//! The budget defaults to half the machine's physical memory ([`default_budget`]); `sss render
//! --max-memory` sets another.

use crate::Error;
use crate::gbuffer::GSample;
use crate::irradiance::{IrradianceSample, IrradianceSettings};
use crate::lights::Incident;
use sss_bssrdf::ModelKind;
use sss_scene::Scene;

/// Used when the physical memory cannot be read (not Linux, or no `/proc/meminfo`).
pub const FALLBACK_BUDGET: u64 = 8 << 30;

/// Bytes per pixel sample at the peak of a render: the G-buffer sample while it is gathered
/// per run of pixels and again when flattened, plus an integrator's per-sample values, variances and
/// irradiance (3 × 24 bytes).
pub const BYTES_PER_SAMPLE: u64 = 2 * std::mem::size_of::<GSample>() as u64 + 72;

/// Bytes per pixel at the peak of a render: the hit counts gathered per run of pixels (4, with
/// 20 to spare) and the offset (4), the output images, coverage and the assembly buffer (~110), and the screen-space
/// buffers of the separable pass (~200).
pub const BYTES_PER_PIXEL: u64 = 24 + 4 + 110 + 200;

/// Half the physical memory of this machine (from `/proc/meminfo`), or [`FALLBACK_BUDGET`].
pub fn default_budget() -> u64 {
    physical_memory().map_or(FALLBACK_BUDGET, |b| b / 2)
}

/// Total physical memory in bytes, if the system says.
pub fn physical_memory() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    kib.checked_mul(1024)
}

/// The estimated peak bytes of rendering a `width` × `height` frame with `spp` camera samples
/// per pixel (saturating, so absurd inputs give `u64::MAX`, never an overflow).
pub fn frame_bytes(width: u32, height: u32, spp: u32) -> u64 {
    let pixels = width as u64 * height as u64;
    let samples = pixels.saturating_mul(spp.max(1) as u64);
    samples
        .saturating_mul(BYTES_PER_SAMPLE)
        .saturating_add(pixels.saturating_mul(BYTES_PER_PIXEL))
}

/// `n` bytes for a person: `1.5 GiB`.
pub use sss_util::human_bytes as human;

/// Parses a byte count: a number with an optional suffix K, M, G or T (powers of 1024, `B`
/// and `iB` allowed: `512M`, `8GiB`, `1.5G`, `1000000`).
pub fn parse_bytes(s: &str) -> Result<u64, String> {
    let t = s.trim();
    let upper = t.to_ascii_uppercase();
    let body = upper
        .strip_suffix("IB")
        .or_else(|| upper.strip_suffix('B'))
        .unwrap_or(&upper);
    let (num, scale) = match body.chars().last() {
        Some('K') => (&body[..body.len() - 1], 1u64 << 10),
        Some('M') => (&body[..body.len() - 1], 1 << 20),
        Some('G') => (&body[..body.len() - 1], 1 << 30),
        Some('T') => (&body[..body.len() - 1], 1 << 40),
        _ => (body, 1),
    };
    let v: f64 = num
        .trim()
        .parse()
        .map_err(|_| format!("`{s}` is not a byte count (e.g. 512M, 8G)"))?;
    let bytes = v * scale as f64;
    if !(bytes.is_finite() && bytes >= 1.0) || bytes > u64::MAX as f64 {
        return Err(format!("`{s}` is not a positive byte count"));
    }
    Ok(bytes as u64)
}

/// Fails, naming the resolution, the pixel samples, the bytes needed and the budget, when
/// rendering `scene` would need more than `budget` bytes, or more pixel samples than the
/// G-buffer can index (2³² − 1).
pub fn check_frame(scene: &Scene, budget: u64) -> Result<(), Error> {
    let cam = &scene.camera;
    let spp = cam.pixel_samples.max(1);
    let samples = cam.width as u64 * cam.height as u64 * spp as u64;
    let what = format!(
        "scene {}: resolution {}x{} with {spp} pixel sample(s)",
        scene.name, cam.width, cam.height
    );
    if samples >= u32::MAX as u64 {
        return Err(Error::Input(format!(
            "{what} is {samples} camera samples, more than a frame can hold ({}); lower the \
             resolution or pixel_samples",
            u32::MAX - 1
        )));
    }
    let needed = frame_bytes(cam.width, cam.height, spp);
    if needed > budget {
        return Err(Error::Input(format!(
            "{what} needs about {needed} bytes ({}), over the memory budget of {budget} bytes \
             ({}); lower the resolution or pixel_samples, or raise --max-memory",
            human(needed),
            human(budget)
        )));
    }
    Ok(())
}

/// Bytes per irradiance sample at the peak of [`crate::irradiance::compute`]: the lit sample
/// with its (possibly empty) packet list, the sample again in the object's array, the
/// blue-noise point it came from, and ~64 bytes of the blue-noise placement's grid and
/// candidates (its memory is proportional to the sample count).
pub const BYTES_PER_IRRADIANCE_SAMPLE: u64 = 2 * std::mem::size_of::<IrradianceSample>() as u64
    + std::mem::size_of::<Vec<Incident>>() as u64
    + std::mem::size_of::<sss_hierarchy::SurfaceSample>() as u64
    + 64;

/// Upper bound on the number of points at least `spacing` apart on a surface of `area`: disks
/// of radius spacing/2 around them do not overlap, and no packing of equal disks in the plane
/// is denser than the hexagonal one, π/(2√3) (Thue's theorem; Fejes Tóth 1940), so
/// N ≤ 2·area / (√3·spacing²), plus one. `None` when the spacing is not positive and finite
/// (then only the cap bounds the count).
pub fn packing_bound(area: f64, spacing: f64) -> Option<u64> {
    if !(spacing.is_finite() && spacing > 0.0 && area.is_finite() && area >= 0.0) {
        return None;
    }
    let n = 2.0 * area / (3f64.sqrt() * spacing * spacing);
    // Saturating: f64 → u64 casts clamp, and an absurd count is what the budget is for.
    Some((n.ceil() as u64).saturating_add(1))
}

/// Per translucent object of `scene`: its index, the estimated irradiance-sample count
/// min(`max_samples`, [`packing_bound`] of its area at the requested spacing) and the bytes
/// ([`BYTES_PER_IRRADIANCE_SAMPLE`] each, plus for the directional dipole up to
/// `light_samples` incident packets per light per sample).
pub fn irradiance_estimate(scene: &Scene, settings: &IrradianceSettings) -> Vec<(usize, u64, u64)> {
    (0..scene.objects.len())
        .filter_map(|o| {
            let mat = scene.translucent(o)?;
            let mesh = &scene.objects[o].mesh;
            let area: f64 = mesh
                .triangles
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
                    0.5 * (b - a).cross(c - a).length()
                })
                .filter(|a| a.is_finite())
                .sum();
            let mfp_mm = (0..3)
                .map(|c| 1.0 / mat.medium.sigma_t_reduced(c).max(1e-300))
                .fold(f64::INFINITY, f64::min);
            let spacing = settings.spacing_mfp * mfp_mm * mat.units_per_mm;
            let cap = settings.max_samples as u64;
            let count = packing_bound(area, spacing).map_or(cap, |n| n.min(cap));
            let mut per = BYTES_PER_IRRADIANCE_SAMPLE;
            if mat.model == ModelKind::DirectionalDipole {
                let packets = (scene.lights.len() as u64)
                    .saturating_mul(settings.light_samples.max(1) as u64);
                per = per.saturating_add(
                    packets.saturating_mul(std::mem::size_of::<Incident>() as u64) + 4,
                );
            }
            Some((o, count, count.saturating_mul(per)))
        })
        .collect()
}

/// Fails, naming `--max-samples`, the spacing, the largest object's sample count, the bytes
/// and the budget, when the irradiance samples ([`irradiance_estimate`], summed over the
/// translucent objects) on top of the frame ([`frame_bytes`]) would need more than `budget`.
pub fn check_irradiance(
    scene: &Scene,
    settings: &IrradianceSettings,
    budget: u64,
) -> Result<(), Error> {
    check_irradiance_with(scene, settings, |_| 0, budget)
}

/// [`check_irradiance`] for a method that also builds structures over the samples and pixels
/// (trees): `structures` gives their bytes from the per-object sample estimates
/// ([`irradiance_estimate`]), and they count towards the same budget.
pub fn check_irradiance_with(
    scene: &Scene,
    settings: &IrradianceSettings,
    structures: impl Fn(&[(usize, u64, u64)]) -> u64,
    budget: u64,
) -> Result<(), Error> {
    let cam = &scene.camera;
    let frame = frame_bytes(cam.width, cam.height, cam.pixel_samples);
    let est = irradiance_estimate(scene, settings);
    let samples = est
        .iter()
        .fold(0u64, |a, e| a.saturating_add(e.2))
        .saturating_add(structures(&est));
    let needed = frame.saturating_add(samples);
    if needed > budget {
        let (o, count, _) = est.iter().max_by_key(|e| e.2).copied().unwrap_or_default();
        let name = scene.objects.get(o).map_or("", |ob| ob.name.as_str());
        return Err(Error::Input(format!(
            "scene {}: irradiance samples (--max-samples {}, --spacing {} mean free paths; \
             up to {count} on object `{name}`) and the method's structures over them need \
             about {samples} bytes ({}) on top of the \
             frame's {frame} bytes, over the memory budget of {budget} bytes ({}); lower \
             --max-samples, raise --spacing or raise --max-memory",
            scene.name,
            settings.max_samples,
            settings.spacing_mfp,
            human(samples),
            human(budget)
        )));
    }
    Ok(())
}

/// Fails, naming the method, the bytes and the budget, when the frame of `scene` and the
/// `structures` bytes a method without irradiance samples declares
/// ([`crate::integrators::Integrator::structure_bytes`]: VPLs, per-thread point sets and cuts at
/// their caps) need more than `budget` bytes.
pub fn check_structures(
    scene: &Scene,
    method: &str,
    structures: u64,
    budget: u64,
) -> Result<(), Error> {
    let cam = &scene.camera;
    let frame = frame_bytes(cam.width, cam.height, cam.pixel_samples);
    let needed = frame.saturating_add(structures);
    if needed > budget {
        return Err(Error::Input(format!(
            "scene {}: method {method}'s structures (lights, and per thread its per-pixel \
             points and cut at their caps) need about {structures} bytes ({}) on top of the \
             frame's {frame} bytes, over the memory budget of {budget} bytes ({}); lower the \
             method's caps (e.g. --irradiance-points, --max-pairs, --max-triplets, \
             --max-splits, --vpls), use fewer threads, or raise --max-memory",
            scene.name,
            human(structures),
            human(budget)
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_bytes_scale_with_pixels_and_samples() {
        let one = frame_bytes(100, 100, 1);
        assert_eq!(one, 10_000 * (BYTES_PER_SAMPLE + BYTES_PER_PIXEL));
        let four = frame_bytes(100, 100, 4);
        assert_eq!(four - one, 3 * 10_000 * BYTES_PER_SAMPLE);
        // The example: 100000² pixels is about 10¹⁰ samples, terabytes.
        assert!(frame_bytes(100_000, 100_000, 1) > 1u64 << 40);
        assert_eq!(frame_bytes(u32::MAX, u32::MAX, u32::MAX), u64::MAX);
        // A G-buffer sample is a few dozen f64: the estimate is not off by orders.
        let g = std::mem::size_of::<GSample>() as u64;
        assert!((100..200).contains(&g), "{g}");
    }

    #[test]
    fn byte_counts_parse_with_suffixes() {
        assert_eq!(parse_bytes("1000").unwrap(), 1000);
        assert_eq!(parse_bytes("512M").unwrap(), 512 << 20);
        assert_eq!(parse_bytes("8GiB").unwrap(), 8 << 30);
        assert_eq!(parse_bytes("1.5g").unwrap(), 3 << 29);
        assert_eq!(parse_bytes("2kb").unwrap(), 2048);
        for bad in ["", "x", "-1G", "0", "nanG", "1e30T"] {
            assert!(parse_bytes(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn physical_memory_is_plausible_when_readable() {
        if let Some(b) = physical_memory() {
            assert!(b >= 64 << 20, "{b}");
            assert_eq!(default_budget(), b / 2);
        } else {
            assert_eq!(default_budget(), FALLBACK_BUDGET);
        }
    }
}
