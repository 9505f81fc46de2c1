//! The cached subset reference of a scene: `exact`
//! (the [`reference_method`] of the full reference) on a seeded uniform random subset of
//! [`SUBSET_PIXELS`] pixels with translucent coverage (all of them when there are fewer), so
//! that renders at 1024² and 2048² can be scored without shading every pixel. The MSE over
//! the subset is an unbiased estimate of the full image's, reported with its standard error
//! ([`SubsetReference::error`], `sss_render::metrics::subset_error`).
//!
//! Cached as `target/compare/cache/subset_<name>_<key>.txt`, keyed by the scene text,
//! resolution, seed, subset size, the reference method's settings and [`SUBSET_VERSION`],
//! with a length-and-checksum sidecar ([`checked`]) like every cache entry; a damaged entry
//! is reported and recomputed. The file is text: a header line, `population N`,
//! `seconds S`, `samples K`, then one `pixel r g b` line per subset pixel in increasing pixel
//! order, each value in Rust's shortest round-trip notation (so it reads back to the same
//! bits).

use super::checked::{self, Entry, fnv1a64};
use super::scenes::reference_method;
use super::{Context, Error};
use sss_bssrdf::Rgb;
use sss_render::RenderSettings;
use sss_render::frame::Frame;
use sss_render::integrators::exact::{shade_subset, translucent_pixels};
use sss_render::metrics::{SubsetError, subset_error, subset_pixels};
use sss_render::scene::Scene;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// Pixels in a subset reference (at least 20 000).
pub const SUBSET_PIXELS: usize = 20_000;

/// Bumped whenever the subset reference's values or file layout change.
const SUBSET_VERSION: u32 = 1;

/// First line of a subset reference file.
const HEADER: &str = "sss-subset-reference v1";

/// A subset reference: `values[k]` is `exact`'s subsurface value of pixel `pixels[k]`.
#[derive(Clone, Debug, PartialEq)]
pub struct SubsetReference {
    /// The subset, in increasing order (indices into the row-major image).
    pub pixels: Vec<usize>,
    /// The reference's subsurface value at each subset pixel.
    pub values: Vec<Rgb>,
    /// Pixels with translucent coverage the subset was drawn from.
    pub population: usize,
    /// Seconds to build it (irradiance samples and shading).
    pub seconds: f64,
    /// Irradiance samples it summed over.
    pub samples: usize,
}

impl SubsetReference {
    /// The estimated MSE (and RMSE) of `image`'s subsurface term against the reference, with
    /// standard errors; `image` must have the reference's resolution.
    pub fn error(&self, image: &[Rgb]) -> Result<SubsetError, Error> {
        subset_error(image, &self.pixels, &self.values, self.population)
            .map_err(|e| Error(e.to_string()))
    }
}

/// The subset reference of `scene` (whose file text is `text`): from the cache, or computed
/// and cached. The subset is drawn with the run's seed.
pub fn subset_reference(
    ctx: &Context<'_>,
    scene: &Scene,
    text: &str,
) -> Result<SubsetReference, Error> {
    let cfg = ctx.config;
    let method = reference_method(cfg.quick);
    let key = fnv1a64(
        format!(
            "subset-v{SUBSET_VERSION}|{text}|{}x{}|{}|{SUBSET_PIXELS}|{method:?}",
            scene.camera.width, scene.camera.height, cfg.seed
        )
        .as_bytes(),
    );
    let dir = cfg.cache_dir();
    std::fs::create_dir_all(&dir)
        .map_err(|e| Error(format!("cannot create {}: {e}", dir.display())))?;
    let path = dir.join(format!("subset_{}_{key:016x}.txt", scene.name));
    let image_pixels = scene.camera.width as usize * scene.camera.height as usize;
    if !cfg.fresh {
        let subject = format!("scene {}", scene.name);
        let read = load(&path, image_pixels);
        if let Some(r) = checked::usable(read, &subject, "subset reference", ctx.log) {
            (ctx.log)(&format!("{subject}: subset reference from cache"));
            return Ok(r);
        }
    }
    (ctx.log)(&format!(
        "scene {}: computing the subset reference ({SUBSET_PIXELS} pixels)",
        scene.name
    ));
    let r = compute(scene, cfg.seed, &method.irradiance)
        .map_err(|e| Error(format!("scene {}: subset reference: {e}", scene.name)))?;
    store(&path, &r)?;
    Ok(r)
}

/// Builds the frame, draws the subset and shades it, after the same memory checks as a render.
fn compute(
    scene: &Scene,
    seed: u64,
    irradiance: &sss_render::irradiance::IrradianceSettings,
) -> Result<SubsetReference, sss_render::Error> {
    let budget = RenderSettings::default().max_memory;
    sss_render::check_scene(scene)?;
    sss_render::budget::check_frame(scene, budget)?;
    sss_render::budget::check_irradiance(scene, irradiance, budget)?;
    let t = Instant::now();
    let frame = Frame::prepare(scene, seed);
    let population = translucent_pixels(&frame);
    let pixels = subset_pixels(&population, SUBSET_PIXELS, seed);
    let values = shade_subset(&frame, irradiance, &pixels)?;
    Ok(SubsetReference {
        pixels,
        values,
        population: population.len(),
        seconds: t.elapsed().as_secs_f64(),
        samples: frame.samples_built().0,
    })
}

/// Writes the entry and its sidecar.
fn store(path: &Path, r: &SubsetReference) -> Result<(), Error> {
    let mut s = format!(
        "{HEADER}\npopulation {}\nseconds {:?}\nsamples {}\n",
        r.population, r.seconds, r.samples
    );
    for (p, v) in r.pixels.iter().zip(&r.values) {
        let _ = writeln!(s, "{p} {:?} {:?} {:?}", v[0], v[1], v[2]);
    }
    checked::write_entry(path, s.as_bytes())
}

/// A cached subset reference of an image of `image_pixels` pixels: `Ok(None)` when there is
/// none, `Err(reason)` when it must not be trusted (checksum, layout, a pixel out of order or
/// past the image, a value that is not a finite non-negative number, a subset larger than
/// its population).
fn load(path: &Path, image_pixels: usize) -> Result<Option<SubsetReference>, String> {
    let bytes = match checked::check(path) {
        Entry::Missing => return Ok(None),
        Entry::Corrupt(reason) => return Err(reason),
        Entry::Good(b) => b,
    };
    let text = String::from_utf8(bytes).map_err(|_| "not UTF-8".to_string())?;
    let mut lines = text.lines();
    if lines.next() != Some(HEADER) {
        return Err("unknown header".into());
    }
    let mut field = |name: &str| -> Result<String, String> {
        lines
            .next()
            .and_then(|l| l.strip_prefix(name))
            .and_then(|l| l.strip_prefix(' '))
            .map(str::to_string)
            .ok_or_else(|| format!("no `{name}` line"))
    };
    let population: usize = field("population")?
        .parse()
        .map_err(|_| "malformed population")?;
    let seconds: f64 = field("seconds")?.parse().map_err(|_| "malformed seconds")?;
    let samples: usize = field("samples")?.parse().map_err(|_| "malformed samples")?;
    let (mut pixels, mut values) = (Vec::new(), Vec::new());
    for (k, line) in lines.enumerate() {
        let w: Vec<&str> = line.split(' ').collect();
        let bad = || format!("malformed pixel line {}", k + 1);
        if w.len() != 4 {
            return Err(bad());
        }
        let p: usize = w[0].parse().map_err(|_| bad())?;
        if p >= image_pixels || pixels.last().is_some_and(|&q| q >= p) {
            return Err(format!("pixel {p} out of order or past the image"));
        }
        let mut v: Rgb = [0.0; 3];
        for c in 0..3 {
            v[c] = w[c + 1].parse().map_err(|_| bad())?;
            if !(v[c].is_finite() && v[c] >= 0.0) {
                return Err(bad());
            }
        }
        pixels.push(p);
        values.push(v);
    }
    if pixels.len() > population || !(seconds.is_finite() && seconds >= 0.0) {
        return Err("inconsistent counts".into());
    }
    Ok(Some(SubsetReference {
        pixels,
        values,
        population,
        seconds,
        samples,
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::checked::tests as t;
    use sss_render::render;

    /// A subset reference of the built-in sphere at 24×18: the stored values equal the full
    /// `exact` render's at the subset pixels (here every pixel, fewer than SUBSET_PIXELS),
    /// survive the cache bit for bit, score an image exactly as the full-image MSE, and damage
    /// is detected.
    #[test]
    fn subset_reference_round_trips_and_matches_the_full_render() {
        let mut scene =
            sss_render::scene::builtin("sphere", &sss_render::scene::LoadOptions::default())
                .unwrap();
        scene.camera.width = 24;
        scene.camera.height = 18;
        let method = reference_method(true);
        let r = compute(&scene, 5, &method.irradiance).unwrap();
        let settings = RenderSettings {
            seed: 5,
            ..RenderSettings::default()
        };
        let full = render(
            &scene,
            &method,
            &settings,
            &sss_render::progress::NoProgress,
        )
        .unwrap();
        let px = full.translucent_pixels();
        assert_eq!((r.pixels.clone(), r.population), (px.clone(), px.len()));
        for (&p, v) in r.pixels.iter().zip(&r.values) {
            assert_eq!(*v, full.subsurface[p], "pixel {p}");
        }
        // An image 10 % bright: the estimate is the full MSE, with no sampling error.
        let image: Vec<Rgb> = full.subsurface.iter().map(|v| v.map(|x| 1.1 * x)).collect();
        let e = r.error(&image).unwrap();
        let mse = sss_render::metrics::error_figures(&image, &full.subsurface, &px, 0.05)
            .rmse
            .powi(2);
        assert!(
            (e.mse - mse).abs() <= 1e-12 * mse && e.mse_se == 0.0,
            "{e:?} vs {mse}"
        );

        let d = t::scratch("subset");
        let path = d.join("subset_sphere_0.txt");
        assert_eq!(load(&path, 24 * 18), Ok(None));
        store(&path, &r).unwrap();
        assert_eq!(load(&path, 24 * 18), Ok(Some(r.clone())));
        // Another (smaller) image is not this entry.
        assert!(load(&path, 10).is_err());
        let len = std::fs::metadata(&path).unwrap().len();
        t::flip_byte(&path, len as usize - 3);
        assert_eq!(load(&path, 24 * 18), Err("checksum mismatch".into()));
        store(&path, &r).unwrap();
        t::truncate(&path, len / 2);
        assert!(load(&path, 24 * 18).unwrap_err().contains("expected"));
        std::fs::remove_dir_all(&d).unwrap();
    }
}
