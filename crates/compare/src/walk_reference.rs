//! The Monte Carlo reference of each (preset, channel), computed once and cached on disk.
//!
//! Each channel is its own simulation with its own radial range: r_max is the radius holding
//! [`R_MAX_ENERGY`] of the standard dipole's reflectance in that channel, so the bins resolve
//! the profile where it carries energy. The Monte Carlo code seeds its streams from
//! (seed, channel, chunk), so a single-channel run gives the same numbers as that channel of
//! a three-channel run.
//!
//! Cache files live in `<out>/cache/` and are named by everything that determines their
//! content: preset, channel, photons, seed, bins, r_max (shortest round-trip notation) and
//! [`CACHE_VERSION`]. Numbers are stored in round-trip notation, so a cached reference is
//! bit-identical to a fresh one. Each file has a length-and-checksum sidecar
//! ([`super::checked`]); a file that fails the check is reported and recomputed.

use super::checked::{self, Entry};
use super::{Config, Error};
use sss_bssrdf::monte_carlo::{self, BinSpacing, WalkConfig};
use sss_bssrdf::presets::Preset;
use sss_bssrdf::{Medium, ModelKind, make_model};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Fraction of the standard dipole's diffuse reflectance inside r_max.
pub const R_MAX_ENERGY: f64 = 0.99;

/// Bump when the cache file layout (or the meaning of its key) changes.
pub const CACHE_VERSION: u32 = 3;

/// Channel names used in file names, CSV and the report.
pub const CHANNEL_NAMES: [&str; 3] = ["r", "g", "b"];

/// The reference profile of one channel.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelReference {
    /// Outer radius of the bins (mm).
    pub r_max: f64,
    /// `bins + 1` bin edges (mm).
    pub edges: Vec<f64>,
    /// Area-averaged R_d of each bin (1/mm²).
    pub rd: Vec<f64>,
    /// Standard error of each bin.
    pub se: Vec<f64>,
    /// The single-scattering part of `rd` (photons that escaped after one collision).
    pub rd_single: Vec<f64>,
    /// Total diffuse reflectance (all radii).
    pub total: f64,
    /// Its standard error.
    pub total_se: f64,
    /// The single-scattering part of `total`.
    pub total_single: f64,
    /// Photons stopped by the event cap.
    pub capped: u64,
    /// Seconds the simulation took (when it ran in this process).
    pub seconds: Option<f64>,
}

/// Which part of the Monte Carlo transport a method is measured against.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WalkPart {
    /// Everything that escaped (single and multiple scattering).
    All,
    /// Multiple scattering only: the total minus the photons that escaped after exactly one
    /// collision. Diffusion models (the dipoles) approximate this part.
    Multiple,
}

impl WalkPart {
    /// Name in the CSV and report (`all`, `multiple`).
    pub fn name(self) -> &'static str {
        match self {
            WalkPart::All => "all",
            WalkPart::Multiple => "multiple",
        }
    }
}

impl ChannelReference {
    /// The binned R_d of `part`.
    pub fn rd_of(&self, part: WalkPart) -> Vec<f64> {
        match part {
            WalkPart::All => self.rd.clone(),
            WalkPart::Multiple => self
                .rd
                .iter()
                .zip(&self.rd_single)
                .map(|(t, s)| (t - s).max(0.0))
                .collect(),
        }
    }

    /// The total diffuse reflectance of `part`.
    pub fn total_of(&self, part: WalkPart) -> f64 {
        match part {
            WalkPart::All => self.total,
            WalkPart::Multiple => (self.total - self.total_single).max(0.0),
        }
    }

    /// Bin centres (mm).
    pub fn centers(&self) -> Vec<f64> {
        self.edges.windows(2).map(|e| 0.5 * (e[0] + e[1])).collect()
    }

    /// Annulus area of each bin (mm²).
    pub fn areas(&self) -> Vec<f64> {
        self.edges
            .windows(2)
            .map(|e| std::f64::consts::PI * (e[1] * e[1] - e[0] * e[0]))
            .collect()
    }
}

/// The reference of one preset.
#[derive(Clone, Debug)]
pub struct PresetReference {
    /// The measured material.
    pub preset: &'static Preset,
    /// Its medium (g = 0, η = 1.3).
    pub medium: Medium,
    /// Red, green, blue.
    pub channels: [ChannelReference; 3],
}

/// r_max of channel `ch`: the standard dipole's radius holding [`R_MAX_ENERGY`], guarded
/// against degenerate answers (falls back to 50 reduced mean free paths).
pub fn r_max_for(medium: &Medium, ch: usize) -> f64 {
    let model = make_model(ModelKind::StandardDipole, medium);
    let r = model.radius_for_energy(ch, R_MAX_ENERGY);
    let mfp = medium.reduced_mean_free_path(ch);
    if r.is_finite() && r > 0.0 {
        r
    } else {
        50.0 * mfp
    }
}

fn cache_path(dir: &Path, preset: &str, ch: usize, cfg: &WalkConfig) -> PathBuf {
    dir.join(format!(
        "mc-v{CACHE_VERSION}-{preset}-{}-p{}-s{}-b{}-r{:e}.csv",
        CHANNEL_NAMES[ch], cfg.photons, cfg.seed, cfg.bins, cfg.r_max
    ))
}

fn key_line(preset: &str, ch: usize, cfg: &WalkConfig) -> String {
    format!(
        "# sss monte-carlo reference v{CACHE_VERSION}: preset={preset} channel={} photons={} seed={} bins={} r_max={:e}",
        CHANNEL_NAMES[ch], cfg.photons, cfg.seed, cfg.bins, cfg.r_max
    )
}

fn serialize(key: &str, r: &ChannelReference) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "{key}");
    let _ = writeln!(s, "# total,total_se,total_single,capped");
    let _ = writeln!(
        s,
        "{:e},{:e},{:e},{}",
        r.total, r.total_se, r.total_single, r.capped
    );
    let _ = writeln!(s, "# r0_mm,r1_mm,rd,se,rd_single");
    for i in 0..r.rd.len() {
        let _ = writeln!(
            s,
            "{:e},{:e},{:e},{:e},{:e}",
            r.edges[i],
            r.edges[i + 1],
            r.rd[i],
            r.se[i],
            r.rd_single[i]
        );
    }
    s
}

/// Parses a cache file; `None` when it does not match `key` or is malformed (then the
/// reference is recomputed).
fn deserialize(text: &str, key: &str, cfg: &WalkConfig) -> Option<ChannelReference> {
    let mut lines = text.lines();
    if lines.next()? != key {
        return None;
    }
    lines.next()?;
    let head: Vec<&str> = lines.next()?.split(',').collect();
    if head.len() != 4 {
        return None;
    }
    let total: f64 = head[0].parse().ok()?;
    let total_se: f64 = head[1].parse().ok()?;
    let total_single: f64 = head[2].parse().ok()?;
    let capped: u64 = head[3].parse().ok()?;
    lines.next()?;
    let mut edges = Vec::with_capacity(cfg.bins + 1);
    let mut rd = Vec::with_capacity(cfg.bins);
    let mut se = Vec::with_capacity(cfg.bins);
    let mut rd_single = Vec::with_capacity(cfg.bins);
    for line in lines {
        let v: Vec<f64> = line
            .split(',')
            .map(|x| x.parse::<f64>())
            .collect::<Result<_, _>>()
            .ok()?;
        if v.len() != 5 || !v.iter().all(|x| x.is_finite()) {
            return None;
        }
        if edges.is_empty() {
            edges.push(v[0]);
        }
        edges.push(v[1]);
        rd.push(v[2]);
        se.push(v[3]);
        rd_single.push(v[4]);
    }
    if rd.len() != cfg.bins
        || ![total, total_se, total_single]
            .iter()
            .all(|x| x.is_finite())
    {
        return None;
    }
    Some(ChannelReference {
        r_max: cfg.r_max,
        edges,
        rd,
        se,
        rd_single,
        total,
        total_se,
        total_single,
        capped,
        seconds: None,
    })
}

/// A cached channel reference: `Ok(None)` when there is none, `Err(reason)` when the file
/// must not be trusted (it fails its checksum, or does not parse as the reference of `key`).
fn load_cached(
    path: &Path,
    key: &str,
    cfg: &WalkConfig,
) -> Result<Option<ChannelReference>, String> {
    match checked::check(path) {
        Entry::Missing => Ok(None),
        Entry::Corrupt(reason) => Err(reason),
        Entry::Good(bytes) => {
            let text = String::from_utf8(bytes).map_err(|_| "not UTF-8 text".to_string())?;
            deserialize(&text, key, cfg)
                .map(Some)
                .ok_or_else(|| "malformed or for other settings".into())
        }
    }
}

/// Loads or computes the references of every preset of `config`. `log` receives one line
/// per channel; `on_photons(done, total)` reports simulation progress.
pub fn load_or_compute(
    config: &Config,
    presets: &[&'static Preset],
    log: &dyn Fn(&str),
    bar: &indicatif::ProgressBar,
) -> Result<Vec<PresetReference>, Error> {
    let dir = config.cache_dir();
    std::fs::create_dir_all(&dir)
        .map_err(|e| Error(format!("cannot create '{}': {e}", dir.display())))?;
    let mut out = Vec::with_capacity(presets.len());
    for preset in presets {
        let medium = Medium::preset(preset.name).map_err(|e| Error(e.to_string()))?;
        let mut channels = Vec::with_capacity(3);
        for (ch, channel_name) in CHANNEL_NAMES.iter().enumerate() {
            let cfg = WalkConfig {
                photons: config.photons,
                seed: config.seed,
                r_max: r_max_for(&medium, ch),
                bins: config.bins,
                channels: std::array::from_fn(|c| c == ch),
                spacing: BinSpacing::Linear,
            };
            let path = cache_path(&dir, preset.name, ch, &cfg);
            let key = key_line(preset.name, ch, &cfg);
            let cached = if config.fresh {
                None
            } else {
                let subject = format!("{} {}", preset.name, channel_name);
                let read = load_cached(&path, &key, &cfg);
                checked::usable(read, &subject, "Monte Carlo reference", log)
            };
            let reference = match cached {
                Some(r) => {
                    log(&format!(
                        "{} {}: Monte Carlo reference from cache (r_max {:.3} mm)",
                        preset.name, channel_name, cfg.r_max
                    ));
                    r
                }
                None => {
                    bar.set_message(format!("{} {}", preset.name, channel_name));
                    let base = bar.position();
                    let t0 = Instant::now();
                    let mc = monte_carlo::simulate_with_progress(&medium, &cfg, &|n| {
                        bar.set_position(base + n)
                    })
                    .map_err(|e| Error(format!("Monte Carlo for {}: {e}", preset.name)))?;
                    bar.set_position(base + cfg.photons);
                    let seconds = t0.elapsed().as_secs_f64();
                    let r = ChannelReference {
                        r_max: cfg.r_max,
                        edges: mc.bin_edges.clone(),
                        rd: mc.rd[ch].clone(),
                        se: mc.se[ch].clone(),
                        rd_single: mc.rd_single[ch].clone(),
                        total: mc.total[ch],
                        total_se: mc.total_se[ch],
                        total_single: mc.total_single[ch],
                        capped: mc.capped,
                        seconds: Some(seconds),
                    };
                    checked::write_entry(&path, serialize(&key, &r).as_bytes())?;
                    log(&format!(
                        "{} {}: Monte Carlo reference, {} photons in {seconds:.1} s (r_max {:.3} mm)",
                        preset.name, channel_name, cfg.photons, cfg.r_max
                    ));
                    r
                }
            };
            channels.push(reference);
        }
        let channels: [ChannelReference; 3] = channels
            .try_into()
            .map_err(|_| Error("internal: three channels expected".into()))?;
        out.push(PresetReference {
            preset,
            medium,
            channels,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cache_round_trip_is_exact() {
        let cfg = WalkConfig {
            photons: 10,
            seed: 3,
            r_max: 0.1 + 0.2,
            bins: 2,
            channels: [true, false, false],
            spacing: BinSpacing::Linear,
        };
        let r = ChannelReference {
            r_max: cfg.r_max,
            edges: vec![0.0, 0.15000000000000002, 0.30000000000000004],
            rd: vec![1.0 / 3.0, 1e-300],
            se: vec![0.1, 0.0],
            rd_single: vec![0.125, 0.0],
            total: 0.7,
            total_se: 0.01,
            total_single: 0.2,
            capped: 2,
            seconds: None,
        };
        let key = key_line("skin1", 0, &cfg);
        let text = serialize(&key, &r);
        assert_eq!(deserialize(&text, &key, &cfg), Some(r));
        // Another key or a truncated file is rejected.
        assert_eq!(deserialize(&text, &key_line("skin2", 0, &cfg), &cfg), None);
        let cut: String = text.lines().take(5).collect::<Vec<_>>().join("\n");
        assert_eq!(deserialize(&cut, &key, &cfg), None);
        let parsed = deserialize(&text, &key, &cfg).unwrap();
        assert_eq!(
            parsed.rd_of(WalkPart::Multiple),
            vec![1.0 / 3.0 - 0.125, 1e-300]
        );
        assert!((parsed.total_of(WalkPart::Multiple) - 0.5).abs() < 1e-15);
        assert_eq!(parsed.total_of(WalkPart::All), 0.7);
    }

    #[test]
    fn cached_file_is_checked_before_it_is_trusted() {
        use crate::checked::{sum_path, tests as t};
        let cfg = WalkConfig {
            photons: 10,
            seed: 3,
            r_max: 2.0,
            bins: 2,
            channels: [true, false, false],
            spacing: BinSpacing::Linear,
        };
        let r = ChannelReference {
            r_max: cfg.r_max,
            edges: vec![0.0, 1.0, 2.0],
            rd: vec![0.25, 0.125],
            se: vec![0.01, 0.02],
            rd_single: vec![0.0625, 0.0],
            total: 0.5,
            total_se: 0.001,
            total_single: 0.1,
            capped: 0,
            seconds: None,
        };
        let key = key_line("skin1", 0, &cfg);
        let d = t::scratch("mc");
        let p = cache_path(&d, "skin1", 0, &cfg);
        assert_eq!(load_cached(&p, &key, &cfg), Ok(None));
        checked::write_entry(&p, serialize(&key, &r).as_bytes()).unwrap();
        assert_eq!(load_cached(&p, &key, &cfg), Ok(Some(r.clone())));

        // A changed digit still parses (2.5e-1 -> 3.5e-1), so only the checksum catches it.
        let text = serialize(&key, &r);
        let at = text.find("2.5e-1").unwrap();
        t::flip_byte(&p, at); // '2' ^ 1 = '3'
        let altered = std::fs::read_to_string(&p).unwrap();
        assert!(deserialize(&altered, &key, &cfg).is_some_and(|a| a.rd[0] == 0.35));
        assert_eq!(
            load_cached(&p, &key, &cfg),
            Err("checksum mismatch".to_string())
        );

        // Cut after the first bin's line: the parser alone would reject it too (1 bin of 2),
        // but the length check names the cause.
        checked::write_entry(&p, text.as_bytes()).unwrap();
        let cut = text.lines().take(5).map(|l| l.len() + 1).sum::<usize>() as u64;
        t::truncate(&p, cut);
        assert_eq!(
            load_cached(&p, &key, &cfg),
            Err(format!("{cut} bytes, {} expected", text.len()))
        );

        checked::write_entry(&p, text.as_bytes()).unwrap();
        std::fs::remove_file(sum_path(&p)).unwrap();
        assert_eq!(
            load_cached(&p, &key, &cfg),
            Err("no checksum file".to_string())
        );

        // A sealed file for other settings is not taken either.
        checked::write_entry(&p, text.as_bytes()).unwrap();
        let other = key_line("skin2", 0, &cfg);
        assert!(load_cached(&p, &other, &cfg).is_err());
        std::fs::remove_dir_all(&d).unwrap();
    }
}
