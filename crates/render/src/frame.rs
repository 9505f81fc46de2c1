//! The prepared frame every integrator works on: the scene, one BVH per object, the G-buffer,
//! the translucent objects the camera sees with their materials' shading data, and (built on
//! first request, then shared) the irradiance samples of those objects. It also keeps the
//! timings of its stages.

use crate::gbuffer::{GBuffer, GSample};
use crate::geometry::SceneGeometry;
use crate::irradiance::{self, IrradianceSettings, ObjectSamples};
use crate::lights::{Incident, Receiver, gather};
use crate::rng::{Stream, rng};
use crate::shading::{TranslucentShading, shading_for};
use sss_bssrdf::Rgb;
use sss_scene::{MaterialKind, Scene};
use std::f64::consts::PI;
use std::sync::{Arc, Mutex, PoisonError};
use std::time::Instant;

/// Wall-clock time of one stage.
#[derive(Clone, Debug, PartialEq)]
pub struct Stage {
    /// Stage name (`bvh`, `gbuffer`, `models`, `samples`, `shading`, ...).
    pub name: &'static str,
    /// Seconds.
    pub seconds: f64,
}

/// Irradiance samples built for one setting.
struct CachedSamples {
    settings: IrradianceSettings,
    samples: Arc<Vec<ObjectSamples>>,
}

/// Samples lit also by the light the surfaces trade, for one setting, with the gather's
/// figures (name, value).
struct CachedBounces {
    settings: IrradianceSettings,
    samples: Arc<Vec<ObjectSamples>>,
    figures: Vec<(&'static str, f64)>,
}

/// What [`Frame::bounced_samples`] keeps: the samples and the gather's figures (name, value).
pub type Bounced = (Arc<Vec<ObjectSamples>>, Vec<(&'static str, f64)>);

/// The parts of a render every integrator shares. Built by [`Frame::prepare`]; integrators
/// read it (and may ask for irradiance samples) through a shared reference.
pub struct Frame<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Seed of every random stream of the render.
    pub seed: u64,
    /// Per-object BVHs.
    pub geom: SceneGeometry,
    /// The camera's hits.
    pub gbuffer: GBuffer,
    /// Translucent objects with at least one G-buffer sample, ascending.
    pub visible: Vec<u32>,
    /// Shading data per material (None for materials no visible translucent object uses).
    pub shading: Vec<Option<TranslucentShading>>,
    stages: Mutex<Vec<Stage>>,
    samples: Mutex<Option<CachedSamples>>,
    bounced: Mutex<Option<CachedBounces>>,
    warnings: Mutex<Vec<String>>,
}

impl<'a> Frame<'a> {
    /// Builds the BVHs, casts the camera rays and builds the models of the translucent
    /// materials the camera sees. It allocates for every camera sample: check the frame
    /// against a memory budget first ([`crate::budget::check_frame`], which
    /// [`crate::render`] does).
    pub fn prepare(scene: &'a Scene, seed: u64) -> Frame<'a> {
        let mut stages = Vec::new();
        let geom = timed_into(&mut stages, "bvh", || SceneGeometry::new(scene));
        let gbuffer = timed_into(&mut stages, "gbuffer", || GBuffer::new(scene, &geom, seed));
        let mut seen = vec![false; scene.objects.len()];
        for g in &gbuffer.samples {
            seen[g.object as usize] = true;
        }
        let visible: Vec<u32> = (0..scene.objects.len() as u32)
            .filter(|&o| seen[o as usize] && scene.translucent(o as usize).is_some())
            .collect();
        let shading = timed_into(&mut stages, "models", || shading_for(scene, &visible));
        let warnings = visible
            .iter()
            .filter_map(|&o| implausible_size(scene, &geom, o))
            .collect();
        Frame {
            scene,
            seed,
            geom,
            gbuffer,
            visible,
            shading,
            stages: Mutex::new(stages),
            samples: Mutex::new(None),
            bounced: Mutex::new(None),
            warnings: Mutex::new(warnings),
        }
    }
}

impl Frame<'_> {
    /// Runs `f` and records its wall-clock time as stage `name`.
    pub fn timed<T>(&self, name: &'static str, f: impl FnOnce() -> T) -> T {
        let t = Instant::now();
        let v = f();
        self.record(name, t.elapsed().as_secs_f64());
        v
    }

    /// Records `seconds` as stage `name`.
    pub fn record(&self, name: &'static str, seconds: f64) {
        self.stages
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .push(Stage { name, seconds });
    }

    /// Records a warning for the caller (a cap that bound, implausible units, ...): one line
    /// for a person, saying what was requested, what was used and how to change it.
    pub fn warn(&self, message: String) {
        let mut w = self.warnings.lock().unwrap_or_else(PoisonError::into_inner);
        if !w.contains(&message) {
            w.push(message);
        }
    }

    /// The warnings recorded so far, in order.
    pub fn warnings(&self) -> Vec<String> {
        self.warnings
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
    }

    /// The stages recorded so far, in order.
    pub fn stages(&self) -> Vec<Stage> {
        self.stages
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone()
    }

    /// The shading data of the translucent object `object`, if it is translucent and visible.
    pub fn shading_of(&self, object: u32) -> Option<&TranslucentShading> {
        self.shading[self.scene.objects[object as usize].material].as_ref()
    }

    /// The pixels with at least one G-buffer sample on a visible translucent object, in
    /// increasing order: the pixels with translucent coverage
    /// ([`crate::pipeline::RenderOutput::translucent_pixels`] of a render of this frame).
    pub fn translucent_pixels(&self) -> Vec<usize> {
        let gb = &self.gbuffer;
        (0..gb.pixels())
            .filter(|&i| {
                gb.pixel(i)
                    .iter()
                    .any(|g| self.shading_of(g.object).is_some())
            })
            .collect()
    }

    /// The irradiance samples of the visible translucent objects for `settings`: placed and lit
    /// on the first request (timed as stage `samples`), then shared by later requests with the
    /// same settings. A request with other settings builds (and keeps) a new set.
    pub fn irradiance_samples(&self, settings: &IrradianceSettings) -> Arc<Vec<ObjectSamples>> {
        let mut cache = self.samples.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some(c) = cache.as_ref()
            && c.settings == *settings
        {
            return Arc::clone(&c.samples);
        }
        let samples = Arc::new(self.timed("samples", || {
            irradiance::compute_for(
                self.scene,
                &self.geom,
                &self.visible,
                settings,
                self.seed,
                &self.shaded_points(),
            )
        }));
        for s in samples.iter().filter(|s| s.capped(settings)) {
            self.warn(cap_warning(self.scene, s, settings));
        }
        *cache = Some(CachedSamples {
            settings: *settings,
            samples: Arc::clone(&samples),
        });
        samples
    }

    /// The irradiance samples lit also by the light the surfaces trade for `settings`
    /// (`settings.bounces` > 0), built by `make` on the first request and shared by later
    /// requests with the same settings (the point sums build them:
    /// `crate::integrators::point_sums::lit_samples`), with the figures `make` returned.
    pub fn bounced_samples<E>(
        &self,
        settings: &IrradianceSettings,
        make: impl FnOnce() -> Result<(Vec<ObjectSamples>, Vec<(&'static str, f64)>), E>,
    ) -> Result<Bounced, E> {
        let mut cache = self.bounced.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some(c) = cache.as_ref()
            && c.settings == *settings
        {
            return Ok((Arc::clone(&c.samples), c.figures.clone()));
        }
        let (samples, figures) = make()?;
        let samples = Arc::new(samples);
        *cache = Some(CachedBounces {
            settings: *settings,
            samples: Arc::clone(&samples),
            figures: figures.clone(),
        });
        Ok((samples, figures))
    }

    /// Per visible translucent object (in [`Frame::visible`]'s order), the G-buffer samples on
    /// it, the points a method shades, and its profile's reach: where its irradiance samples
    /// are needed ([`irradiance::compute_for`]).
    pub fn shaded_points(&self) -> Vec<irradiance::ShadedPoints> {
        let mut out: Vec<irradiance::ShadedPoints> = self
            .visible
            .iter()
            .map(|&o| irradiance::ShadedPoints {
                points: Vec::new(),
                reach: self.shading_of(o).map_or(f64::INFINITY, |sh| {
                    irradiance::reach(sh.bssrdf(), sh.units_per_mm)
                }),
            })
            .collect();
        // One pass over the G-buffer (`visible` is ascending).
        for g in &self.gbuffer.samples {
            if let Ok(k) = self.visible.binary_search(&g.object) {
                out[k].points.push(g.p);
            }
        }
        out
    }

    /// About how many irradiance samples the ones built so far left out as out of reach of
    /// every shaded point ([`irradiance::ObjectSamples::left_out`], summed over objects).
    pub fn samples_left_out(&self) -> usize {
        let cache = self.samples.lock().unwrap_or_else(PoisonError::into_inner);
        cache
            .as_ref()
            .map_or(0, |c| c.samples.iter().map(|s| s.left_out).sum())
    }

    /// The irradiance samples built so far (count summed over objects, and each object's
    /// spacing), or `(0, [])` when no integrator asked for them.
    pub fn samples_built(&self) -> (usize, Vec<(u32, f64)>) {
        let cache = self.samples.lock().unwrap_or_else(PoisonError::into_inner);
        match cache.as_ref() {
            Some(c) => (
                c.samples.iter().map(|s| s.samples.len()).sum(),
                c.samples.iter().map(|s| (s.object, s.spacing)).collect(),
            ),
            None => (0, Vec::new()),
        }
    }

    /// The irradiance samples of object `object` in `samples`, indexed by object.
    pub fn samples_by_object<'s>(
        &self,
        samples: &'s [ObjectSamples],
    ) -> Vec<Option<&'s ObjectSamples>> {
        (0..self.scene.objects.len() as u32)
            .map(|o| samples.iter().find(|s| s.object == o))
            .collect()
    }

    /// Direct light reflected by an opaque diffuse surface at `g` towards the camera.
    pub fn shade_opaque(&self, g: &GSample, light_samples: u32) -> Rgb {
        self.shade_opaque_with(g, light_samples, &mut Vec::new())
    }

    /// [`Self::shade_opaque`] with a caller's buffer for the incident light (cleared first), so
    /// that a loop over many samples allocates once. The result is the same.
    pub fn shade_opaque_with(
        &self,
        g: &GSample,
        light_samples: u32,
        packets: &mut Vec<Incident>,
    ) -> Rgb {
        let mat = &self.scene.materials[self.scene.objects[g.object as usize].material];
        let MaterialKind::Diffuse { albedo, texture } = &mat.kind else {
            return [0.0; 3];
        };
        let tex = texture.as_ref().map_or([1.0; 3], |t| t.eval(g.p));
        // Light the side the camera sees.
        let (n, ng) = if g.ng.dot(g.wo) >= 0.0 {
            (g.n, g.ng)
        } else {
            (-g.n, -g.ng)
        };
        let idx = g.pixel as u64 * self.gbuffer.samples_per_pixel as u64 + g.index as u64;
        let mut r = rng(self.seed, Stream::Opaque, idx);
        packets.clear();
        gather(
            &self.geom,
            &self.scene.lights,
            Receiver { p: g.p, n, ng },
            light_samples,
            &mut r,
            packets,
        );
        let mut out = [0.0; 3];
        for p in packets.iter() {
            for c in 0..3 {
                out[c] += albedo[c] * tex[c] / PI * p.e_cos[c];
            }
        }
        out
    }
}

/// The warning for an object whose irradiance samples the per-object cap made coarser than
/// requested: requested and effective spacing in mean free paths, and how to lift the cap.
fn cap_warning(scene: &Scene, s: &ObjectSamples, settings: &IrradianceSettings) -> String {
    let object = &scene.objects[s.object as usize];
    let material = &scene.materials[object.material].name;
    let used_mfp = s.spacing / s.mfp.max(1e-300);
    // The count grows as 1/spacing² on a surface.
    let ratio = (s.spacing / s.requested_spacing(settings).max(1e-300)).powi(2);
    let needed = (s.samples.len() as f64 * ratio).ceil();
    let needed = if needed < 1e9 {
        format!("about {needed:.0}")
    } else if needed.is_finite() {
        format!("about {needed:.1e}")
    } else {
        "far more than can be placed".to_string()
    };
    format!(
        "object `{}` (material `{material}`): the cap of {} irradiance samples per object bound, \
        so samples are {used_mfp:.3} mean free paths apart instead of the requested {}; raise \
        --max-samples to {needed} (or check the material's units_per_mm) to lift it",
        object.name, settings.max_samples, settings.spacing_mfp
    )
}

/// Objects this many reduced mean free paths across or more are implausibly large.
pub const MAX_PLAUSIBLE_MFP: f64 = 1e4;

/// A warning when translucent object `o` is smaller than one reduced mean free path across or
/// larger than [`MAX_PLAUSIBLE_MFP`] of them: almost always a `units_per_mm` mistake (the
/// model then sees a speck of translucent material, or an opaque wall).
fn implausible_size(scene: &Scene, geom: &SceneGeometry, o: u32) -> Option<String> {
    let t = scene.translucent(o as usize)?;
    let object = &scene.objects[o as usize];
    let (lo, hi) = geom.bounds(o)?;
    let size = (hi - lo).max_element();
    if !(size.is_finite() && size > 0.0 && t.units_per_mm > 0.0) {
        return None;
    }
    // Reduced mean free paths over the channels: the scales the light spreads on.
    let mfp = |c: usize| 1.0 / t.medium.sigma_t_reduced(c).max(1e-300);
    let mfp_min = (0..3).map(mfp).fold(f64::INFINITY, f64::min);
    let mfp_max = (0..3).map(mfp).fold(0.0, f64::max);
    let size_mm = size / t.units_per_mm;
    let material = &scene.materials[object.material].name;
    // Smaller than the shortest one in every channel, or larger than 10⁴ of the longest.
    let (across, what) = if size_mm < mfp_min {
        (size_mm / mfp_min, "smaller than one")
    } else if size_mm > MAX_PLAUSIBLE_MFP * mfp_max {
        (size_mm / mfp_max, "larger than 10⁴")
    } else {
        return None;
    };
    Some(format!(
        "object `{}` (material `{material}`) is {across:.3e} reduced mean free paths across, \
        {what}: with units_per_mm = {} it measures {size_mm:.3e} mm; check units_per_mm",
        object.name, t.units_per_mm
    ))
}

fn timed_into<T>(stages: &mut Vec<Stage>, name: &'static str, f: impl FnOnce() -> T) -> T {
    let t = Instant::now();
    let v = f();
    stages.push(Stage {
        name,
        seconds: t.elapsed().as_secs_f64(),
    });
    v
}

/// A sample's value as a pixel counts it: non-finite or negative values count as 0.
#[inline]
pub(crate) fn pixel_value(v: f64) -> f64 {
    if v.is_finite() && v > 0.0 { v } else { 0.0 }
}

/// A pixel's subsurface value from its camera samples' values (`None` for samples off
/// translucent objects, which count 0), exactly as [`crate::render`] assembles it: the sum of each
/// sample's value over `samples_per_pixel` (misses count 0 too), non-finite or negative
/// values counting 0. Shared by the
/// renderer and the methods that shade a subset of pixels (`exact::shade_subset`, the VPL
/// methods' `shade_pixels`).
pub fn assembled_subsurface(values: &[Option<Rgb>], samples_per_pixel: u32) -> Rgb {
    let spp = samples_per_pixel as f64;
    let mut sss = [0.0; 3];
    for v in values.iter().flatten() {
        for c in 0..3 {
            sss[c] += pixel_value(v[c]) / spp;
        }
    }
    sss
}
