//! Memory estimated before it is allocated: a render's largest allocations grow with user
//! input (resolution × pixel samples), so [`check_frame`] estimates them from the scene alone
//! and refuses, with one clear error naming the input, the bytes and the budget, a frame that
//! would not fit — instead of an allocation failure that aborts the process.
//!
//! The budget defaults to half the machine's physical memory ([`default_budget`]); `sss render
//! --max-memory` sets another.

use crate::Error;
use crate::gbuffer::GSample;
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
pub fn human(n: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = n as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{n} B")
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

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
    fn human_sizes() {
        assert_eq!(human(512), "512 B");
        assert_eq!(human(1536), "1.5 KiB");
        assert_eq!(human(3 << 30), "3.0 GiB");
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
