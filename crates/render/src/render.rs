//! One render: scene → BVHs → G-buffer → (for the translucent objects the camera sees)
//! models and irradiance samples → an integrator → the subsurface image, the total image and
//! timings by stage.

use crate::gbuffer::{GBuffer, GSample};
use crate::geometry::SceneGeometry;
use crate::integrators::pathtrace::{self, ProbeRadii};
use crate::integrators::separable::{
    MaterialKernel, SeparableSettings, build_kernel, filter_options,
};
use crate::integrators::{TranslucentShading, exact, shading_for};
use crate::irradiance::{self, IrradianceSettings, ObjectSamples};
use crate::lights::{Receiver, background, gather};
use crate::rng::{Stream, rng};
use sss_scene::{MaterialKind, Scene};
use indicatif::ProgressBar;
use rayon::prelude::*;
use sss_bssrdf::Rgb;
use std::f64::consts::PI;
use std::time::Instant;

/// Which integrator computes the subsurface term.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Brute-force sum over every irradiance sample of the object.
    Exact,
    /// BSSRDF importance sampling with probe rays (pbrt §15.4).
    PathTrace,
    /// Screen-space separable blur of the irradiance (Jimenez et al. 2015).
    Separable,
}

impl Method {
    /// The command-line name.
    pub fn name(self) -> &'static str {
        match self {
            Method::Exact => "exact",
            Method::PathTrace => "pathtrace",
            Method::Separable => "separable",
        }
    }
}

/// Everything a render needs besides the scene.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// The integrator.
    pub method: Method,
    /// Path tracer: BSSRDF samples per pixel sample.
    pub spp: u32,
    /// Seed of every random stream.
    pub seed: u64,
    /// Irradiance sample placement and lighting (point-based methods).
    pub irradiance: IrradianceSettings,
    /// Light samples per quad or environment light when shading opaque surfaces.
    pub opaque_light_samples: u32,
    /// The separable integrator's kernel and filter.
    pub separable: SeparableSettings,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            method: Method::Exact,
            spp: 16,
            seed: 1,
            irradiance: IrradianceSettings::default(),
            opaque_light_samples: 16,
            separable: SeparableSettings::default(),
        }
    }
}

/// Wall-clock time of one stage.
#[derive(Clone, Debug, PartialEq)]
pub struct Stage {
    /// Stage name (`bvh`, `gbuffer`, `models`, `samples`, `shading`, ...).
    pub name: &'static str,
    /// Seconds.
    pub seconds: f64,
}

/// The result of a render. Pixel arrays are row-major from the top-left, width·height long,
/// linear RGB, finite and non-negative.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The subsurface term (0 off translucent objects).
    pub subsurface: Vec<Rgb>,
    /// Subsurface on translucent objects, direct diffuse light on opaque ones, the environment
    /// where rays leave the scene.
    pub total: Vec<Rgb>,
    /// Path tracer only: the standard error of each pixel's subsurface estimate.
    pub std_error: Option<Vec<Rgb>>,
    /// Fraction of each pixel's camera samples that landed on a translucent object.
    pub coverage: Vec<f32>,
    /// Timings by stage, in order.
    pub stages: Vec<Stage>,
    /// Irradiance samples used, summed over objects.
    pub irradiance_samples: usize,
    /// Minimum spacing of the irradiance samples per object (object index, scene units).
    pub spacing: Vec<(u32, f64)>,
    /// Separable integrator only: the screen-space buffers it filtered.
    pub screen: Option<ScreenBuffers>,
}

/// The per-pixel inputs of a screen-space pass, in scene units: what `sss render --gbuffer`
/// writes and `sss filter` reads.
#[derive(Clone, Debug, PartialEq)]
pub struct ScreenBuffers {
    /// Fresnel-transmitted, textured irradiance, averaged over the pixel's samples on its
    /// object (0 off translucent objects).
    pub irradiance: Vec<Rgb>,
    /// Distance from the camera (scene units).
    pub depth: Vec<f64>,
    /// World-space size of one pixel at that distance (scene units).
    pub footprint: Vec<f64>,
    /// Translucent object per pixel (its first translucent sample's), `u32::MAX` for none.
    pub object: Vec<u32>,
}

impl RenderOutput {
    /// Total seconds over all stages.
    pub fn seconds_total(&self) -> f64 {
        self.stages.iter().map(|s| s.seconds).sum()
    }

    /// Pixel indices with some translucent coverage: the pixels error figures are taken over.
    pub fn translucent_pixels(&self) -> Vec<usize> {
        (0..self.coverage.len())
            .filter(|&i| self.coverage[i] > 0.0)
            .collect()
    }
}

/// The parts of a render every integrator shares: geometry, G-buffer, the translucent objects
/// seen, their shading data and (for point-based integrators) their irradiance samples.
pub struct Prepared<'a> {
    /// The scene.
    pub scene: &'a Scene,
    /// Per-object BVHs.
    pub geom: SceneGeometry,
    /// The camera's hits.
    pub gbuffer: GBuffer,
    /// Translucent objects with at least one G-buffer sample, ascending.
    pub visible: Vec<u32>,
    /// Shading data per material (None for materials no visible translucent object uses).
    pub shading: Vec<Option<TranslucentShading>>,
    /// Timings so far.
    pub stages: Vec<Stage>,
}

fn timed<T>(stages: &mut Vec<Stage>, name: &'static str, f: impl FnOnce() -> T) -> T {
    let t = Instant::now();
    let v = f();
    stages.push(Stage {
        name,
        seconds: t.elapsed().as_secs_f64(),
    });
    v
}

/// Builds the BVHs, casts the camera rays and builds the models of the translucent materials
/// the camera sees.
pub fn prepare<'a>(scene: &'a Scene, seed: u64) -> Prepared<'a> {
    let mut stages = Vec::new();
    let geom = timed(&mut stages, "bvh", || SceneGeometry::new(scene));
    let gbuffer = timed(&mut stages, "gbuffer", || GBuffer::new(scene, &geom, seed));
    let mut seen = vec![false; scene.objects.len()];
    for g in &gbuffer.samples {
        seen[g.object as usize] = true;
    }
    let visible: Vec<u32> = (0..scene.objects.len() as u32)
        .filter(|&o| seen[o as usize] && scene.translucent(o as usize).is_some())
        .collect();
    let shading = timed(&mut stages, "models", || shading_for(scene, &visible));
    Prepared {
        scene,
        geom,
        gbuffer,
        visible,
        shading,
        stages,
    }
}

impl Prepared<'_> {
    /// The shading data of the translucent object `object`, if it is translucent and visible.
    pub fn shading_of(&self, object: u32) -> Option<&TranslucentShading> {
        self.shading[self.scene.objects[object as usize].material].as_ref()
    }

    /// Places and lights the irradiance samples of the visible translucent objects.
    pub fn irradiance_samples(
        &mut self,
        settings: &IrradianceSettings,
        seed: u64,
    ) -> Vec<ObjectSamples> {
        let (scene, geom, visible) = (self.scene, &self.geom, &self.visible);
        timed(&mut self.stages, "samples", || {
            irradiance::compute(scene, geom, visible, settings, seed)
        })
    }

    /// Direct light reflected by an opaque diffuse surface at `g` towards the camera.
    pub fn shade_opaque(&self, g: &GSample, light_samples: u32, seed: u64) -> Rgb {
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
        let mut r = rng(seed, Stream::Opaque, idx);
        let mut packets = Vec::new();
        gather(
            &self.geom,
            &self.scene.lights,
            Receiver { p: g.p, n, ng },
            light_samples,
            &mut r,
            &mut packets,
        );
        let mut out = [0.0; 3];
        for p in &packets {
            for c in 0..3 {
                out[c] += albedo[c] * tex[c] / PI * p.e_cos[c];
            }
        }
        out
    }

    /// Assembles the output from per-pixel-sample subsurface values (indexed like
    /// `gbuffer.samples`; `None` for samples not on a visible translucent object), shading
    /// opaque samples and adding the background.
    pub fn assemble(
        &mut self,
        subsurface: &[Rgb],
        std_error: Option<Vec<Rgb>>,
        settings: &RenderSettings,
        irradiance_samples: usize,
        spacing: Vec<(u32, f64)>,
    ) -> RenderOutput {
        let gb = &self.gbuffer;
        let spp = gb.samples_per_pixel as f64;
        let bg = background(&self.scene.lights);
        let this = &*self;
        let t = Instant::now();
        let pixels: Vec<(Rgb, Rgb, f32)> = (0..gb.pixels())
            .into_par_iter()
            .map(|i| {
                let (lo, hi) = (gb.offsets[i] as usize, gb.offsets[i + 1] as usize);
                let mut sss = [0.0; 3];
                let mut total = [0.0; 3];
                let mut covered = 0u32;
                for k in lo..hi {
                    let g = &gb.samples[k];
                    let translucent = this.shading_of(g.object).is_some();
                    let v = if translucent {
                        covered += 1;
                        subsurface[k]
                    } else {
                        this.shade_opaque(g, settings.opaque_light_samples, settings.seed)
                    };
                    for c in 0..3 {
                        let v = if v[c].is_finite() && v[c] > 0.0 {
                            v[c]
                        } else {
                            0.0
                        };
                        total[c] += v / spp;
                        if translucent {
                            sss[c] += v / spp;
                        }
                    }
                }
                let misses = (gb.samples_per_pixel as usize).saturating_sub(hi - lo) as f64;
                for c in 0..3 {
                    total[c] += bg[c] * misses / spp;
                }
                (sss, total, covered as f32 / spp as f32)
            })
            .collect();
        let opaque_seconds = t.elapsed().as_secs_f64();
        self.stages.push(Stage {
            name: "opaque",
            seconds: opaque_seconds,
        });
        RenderOutput {
            width: gb.width,
            height: gb.height,
            subsurface: pixels.iter().map(|p| p.0).collect(),
            total: pixels.iter().map(|p| p.1).collect(),
            std_error,
            coverage: pixels.iter().map(|p| p.2).collect(),
            stages: self.stages.clone(),
            irradiance_samples,
            spacing,
            screen: None,
        }
    }
}

/// Renders `scene` with `settings`. `progress`, if given, counts shaded pixel samples. Fails
/// only when the separable integrator cannot build a kernel.
pub fn render(
    scene: &Scene,
    settings: &RenderSettings,
    progress: Option<&ProgressBar>,
) -> Result<RenderOutput, crate::Error> {
    let mut prep = prepare(scene, settings.seed);
    let n = prep.gbuffer.samples.len();
    if let Some(p) = progress {
        p.set_length(n as u64);
    }
    match settings.method {
        Method::Exact => {
            let samples = prep.irradiance_samples(&settings.irradiance, settings.seed);
            let count = samples.iter().map(|s| s.samples.len()).sum();
            let spacing = samples.iter().map(|s| (s.object, s.spacing)).collect();
            let t = Instant::now();
            let by_object: Vec<Option<&ObjectSamples>> = (0..scene.objects.len() as u32)
                .map(|o| samples.iter().find(|s| s.object == o))
                .collect();
            let values: Vec<Rgb> = prep
                .gbuffer
                .samples
                .par_iter()
                .map(|g| {
                    let v = match (prep.shading_of(g.object), by_object[g.object as usize]) {
                        (Some(sh), Some(s)) => exact::shade(g, sh, s),
                        _ => [0.0; 3],
                    };
                    if let Some(p) = progress {
                        p.inc(1);
                    }
                    v
                })
                .collect();
            prep.stages.push(Stage {
                name: "shading",
                seconds: t.elapsed().as_secs_f64(),
            });
            Ok(prep.assemble(&values, None, settings, count, spacing))
        }
        Method::PathTrace => {
            let t = Instant::now();
            let radii: Vec<Option<ProbeRadii>> = prep
                .shading
                .iter()
                .map(|s| s.as_ref().map(ProbeRadii::new))
                .collect();
            let spp = settings.spp.max(1);
            let sampler = |shading, radii| pathtrace::Sampler {
                geom: &prep.geom,
                lights: &scene.lights,
                shading,
                radii,
            };
            let gspp = prep.gbuffer.samples_per_pixel as u64;
            let results: Vec<(Rgb, Rgb)> = prep
                .gbuffer
                .samples
                .par_iter()
                .map_init(pathtrace::Scratch::default, |scratch, g| {
                    let m = scene.objects[g.object as usize].material;
                    let (Some(sh), Some(rad)) = (prep.shading[m].as_ref(), radii[m].as_ref())
                    else {
                        return ([0.0; 3], [0.0; 3]);
                    };
                    let mut r = rng(
                        settings.seed,
                        Stream::Path,
                        g.pixel as u64 * gspp + g.index as u64,
                    );
                    let mut sum = [0.0; 3];
                    let mut sum2 = [0.0; 3];
                    for _ in 0..spp {
                        let v = sampler(sh, rad).sample(g, &mut r, scratch);
                        for c in 0..3 {
                            sum[c] += v[c];
                            sum2[c] += v[c] * v[c];
                        }
                    }
                    if let Some(p) = progress {
                        p.inc(1);
                    }
                    let k = spp as f64;
                    let mean = sum.map(|s| s / k);
                    // Variance of the mean of this sample's spp estimates.
                    let var = [0, 1, 2].map(|c| {
                        if spp > 1 {
                            ((sum2[c] - k * mean[c] * mean[c]) / (k - 1.0)).max(0.0) / k
                        } else {
                            0.0
                        }
                    });
                    (mean, var)
                })
                .collect();
            prep.stages.push(Stage {
                name: "shading",
                seconds: t.elapsed().as_secs_f64(),
            });
            let values: Vec<Rgb> = results.iter().map(|r| r.0).collect();
            // Pixel standard error: the pixel averages its samples (1/spp_camera each).
            let gb = &prep.gbuffer;
            let cs = gb.samples_per_pixel as f64;
            let se: Vec<Rgb> = (0..gb.pixels())
                .map(|i| {
                    let mut v = [0.0; 3];
                    for k in gb.offsets[i] as usize..gb.offsets[i + 1] as usize {
                        for c in 0..3 {
                            v[c] += results[k].1[c] / (cs * cs);
                        }
                    }
                    v.map(|x| x.sqrt())
                })
                .collect();
            Ok(prep.assemble(&values, Some(se), settings, 0, Vec::new()))
        }
        Method::Separable => render_separable(&mut prep, settings, progress),
    }
}

/// The separable integrator (see [`crate::integrators::separable`]): irradiance at the pixels,
/// a kernel per visible translucent material, one screen-space filter run per material.
fn render_separable(
    prep: &mut Prepared<'_>,
    settings: &RenderSettings,
    progress: Option<&ProgressBar>,
) -> Result<RenderOutput, crate::Error> {
    use sss_separable::{NO_OBJECT, ScreenInput, convolve2d, screen_space};
    let scene = prep.scene;
    // Fresnel-transmitted, textured irradiance at every translucent pixel sample.
    let t = Instant::now();
    let light_samples = settings.irradiance.light_samples;
    let irradiance: Vec<Rgb> = prep
        .gbuffer
        .samples
        .par_iter()
        .enumerate()
        .map(|(k, g)| {
            let Some(sh) = prep.shading_of(g.object) else {
                return [0.0; 3];
            };
            let mut r = rng(settings.seed, Stream::Irradiance, (1u64 << 62) ^ k as u64);
            let mut packets = Vec::new();
            let at = Receiver {
                p: g.p,
                n: g.n,
                ng: g.ng,
            };
            gather(
                &prep.geom,
                &scene.lights,
                at,
                light_samples,
                &mut r,
                &mut packets,
            );
            let tex = sh.texture.as_ref().map_or([1.0; 3], |t| t.eval(g.p));
            let mut e = [0.0; 3];
            for p in &packets {
                let ft = sss_bssrdf::fresnel::ft_dielectric(g.n.dot(p.dir), sh.eta);
                for c in 0..3 {
                    e[c] += ft * p.e_cos[c] * tex[c];
                }
            }
            e
        })
        .collect();
    prep.stages.push(Stage {
        name: "irradiance",
        seconds: t.elapsed().as_secs_f64(),
    });
    // One kernel per material in use.
    let t = Instant::now();
    let mut kernels: Vec<Option<MaterialKernel>> = Vec::new();
    for (m, sh) in prep.shading.iter().enumerate() {
        kernels.push(match sh {
            Some(sh) => Some(
                build_kernel(sh.model.as_ref(), &settings.separable).map_err(|e| {
                    crate::Error::Input(format!(
                        "material `{}`: cannot build the {} kernel: {e}",
                        scene.materials[m].name, settings.separable.kernel
                    ))
                })?,
            ),
            None => None,
        });
    }
    prep.stages.push(Stage {
        name: "kernels",
        seconds: t.elapsed().as_secs_f64(),
    });
    // Filter each material's pixels.
    let t = Instant::now();
    let gb = &prep.gbuffer;
    let (w, h) = (gb.width as usize, gb.height as usize);
    let screen = screen_buffers(prep, &irradiance);
    let mut values = vec![[0.0; 3]; gb.samples.len()];
    let opts = filter_options(&settings.separable, settings.seed);
    for (m, kernel) in kernels.iter().enumerate() {
        let (Some(kernel), Some(sh)) = (kernel, prep.shading[m].as_ref()) else {
            continue;
        };
        let u = sh.units_per_mm;
        let mut e = vec![[0.0f32; 3]; w * h];
        let mut depth = vec![0.0f32; w * h];
        let mut mask = vec![NO_OBJECT; w * h];
        let mut mm = vec![0.0f32; w * h];
        for i in 0..w * h {
            let o = screen.object[i];
            if o == NO_OBJECT || scene.objects[o as usize].material != m {
                continue;
            }
            mask[i] = o;
            depth[i] = (screen.depth[i] / u) as f32;
            mm[i] = (screen.footprint[i] / u) as f32;
            e[i] = screen.irradiance[i].map(|v| v as f32);
        }
        let input = ScreenInput {
            width: w,
            height: h,
            irradiance: &e,
            depth: &depth,
            mask: &mask,
            mm_per_pixel: &mm,
        };
        let filtered = match kernel {
            MaterialKernel::Separable(k) => screen_space::filter(&input, k, &opts),
            MaterialKernel::Full(k2) => convolve2d::exact(&input, k2, &opts),
        }
        .map_err(|e| crate::Error::Input(format!("separable filter: {e}")))?;
        for (k, g) in gb.samples.iter().enumerate() {
            if scene.objects[g.object as usize].material != m
                || screen.object[g.pixel as usize] != g.object
            {
                continue;
            }
            let f = filtered[g.pixel as usize];
            let s = sss_bssrdf::fresnel::ft_dielectric(g.n.dot(g.wo), sh.eta) * sh.norm;
            values[k] = [f[0] as f64 * s, f[1] as f64 * s, f[2] as f64 * s];
        }
    }
    if let Some(p) = progress {
        p.inc(gb.samples.len() as u64);
    }
    prep.stages.push(Stage {
        name: "shading",
        seconds: t.elapsed().as_secs_f64(),
    });
    let mut out = prep.assemble(&values, None, settings, 0, Vec::new());
    out.screen = Some(screen);
    Ok(out)
}

/// Per pixel: the first translucent sample's object, and the average irradiance, depth and
/// footprint of the pixel's samples on that object.
fn screen_buffers(prep: &Prepared<'_>, irradiance: &[Rgb]) -> ScreenBuffers {
    let gb = &prep.gbuffer;
    let n = gb.pixels();
    let mut b = ScreenBuffers {
        irradiance: vec![[0.0; 3]; n],
        depth: vec![0.0; n],
        footprint: vec![0.0; n],
        object: vec![u32::MAX; n],
    };
    for i in 0..n {
        let range = gb.offsets[i] as usize..gb.offsets[i + 1] as usize;
        let Some(first) = range
            .clone()
            .find(|&k| prep.shading_of(gb.samples[k].object).is_some())
        else {
            continue;
        };
        let o = gb.samples[first].object;
        let mut count = 0.0;
        for k in range {
            let g = &gb.samples[k];
            if g.object != o {
                continue;
            }
            for c in 0..3 {
                b.irradiance[i][c] += irradiance[k][c];
            }
            b.depth[i] += g.distance;
            b.footprint[i] += g.footprint;
            count += 1.0;
        }
        b.object[i] = o;
        b.irradiance[i] = b.irradiance[i].map(|v| v / count);
        b.depth[i] /= count;
        b.footprint[i] /= count;
    }
    b
}
