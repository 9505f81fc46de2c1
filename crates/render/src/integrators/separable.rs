//! The screen-space separable integrator (Jimenez et al. 2015, §6): the Fresnel-transmitted
//! irradiance at each pixel's surface point, blurred in screen space by a separable kernel of
//! the material's R_d (two 1D passes per term, kernel width from the projected pixel size,
//! depth- and object-aware taps, per-pixel jitter of the filter axes), then multiplied by
//! F_t(η, cos θ_o)/(cπ) like every other integrator. The kernel is chosen and built by
//! [`crate::kernel_choice`]; the pass itself is `sss_separable::screen_space` on plain buffers.

use super::{
    Integrator, Layer, Method, MethodOptions, OptionKind, OptionSpec, Shaded, Stat, Sweep,
};
use crate::Error;
use crate::frame::Frame;
use crate::integrators::Converges;
use crate::irradiance::IrradianceSettings;
use crate::kernel_choice::{
    KernelMethod, MaterialKernel, SeparableSettings, build_kernel, filter_options,
};
use crate::lights::{Receiver, gather};
use crate::progress::Progress;
use crate::rng::{Stream, rng};
use rayon::prelude::*;
use sss_bssrdf::Rgb;
use sss_scene::Scene;
use sss_separable::{NO_OBJECT, ScreenInput, convolve2d, screen_space};

/// Pixels (or samples) per parallel task of the per-pixel loops: enough work per task that the
/// scheduling cost is negligible.
const PIXELS_PER_TASK: usize = 4096;

/// The options of `separable` (shared with `sss filter`).
pub const OPTIONS: [OptionSpec; 5] = [
    OptionSpec {
        name: "kernel",
        value_name: "KERNEL",
        default: "preintegrated",
        help: "Separable kernel, or exact2d for the brute-force 2D screen-space convolution",
        kind: OptionKind::Value,
        values: &KernelMethod::NAMES,
    },
    OptionSpec {
        name: "taps",
        value_name: "N",
        default: "7",
        help: "taps per 1D pass",
        kind: OptionKind::Value,
        values: &[],
    },
    OptionSpec {
        name: "uniform-taps",
        value_name: "",
        default: "",
        help: "place taps uniformly instead of by importance",
        kind: OptionKind::Flag,
        values: &[],
    },
    OptionSpec {
        name: "k",
        value_name: "K",
        default: "2",
        help: "guided-optimisation exponent k in [0, 4]",
        kind: OptionKind::Value,
        values: &[],
    },
    OptionSpec {
        name: "jitter",
        value_name: "FRACTION",
        default: "0.1",
        help: "fraction of the kernel support within which the filter axes are \
               rotated per pixel (0 turns the jitter off)",
        kind: OptionKind::Value,
        values: &[],
    },
];

/// The registry entry.
pub const METHOD: Method = Method {
    name: "separable",
    about: "Screen-space separable blur (Jimenez et al. 2015)",
    options: &OPTIONS,
    build: |o| Ok(Box::new(Separable::from_options(o)?)),
    sweep: Sweep {
        option: "taps",
        label: "taps",
        values: |quick| {
            if quick {
                vec![3.0, 7.0, 15.0]
            } else {
                vec![3.0, 7.0, 15.0, 31.0]
            }
        },
    },
    converges_to: Converges::Model,
};

/// Reads and checks the kernel options (`sss render --method separable`, `sss filter`).
pub fn kernel_settings(o: &MethodOptions) -> Result<SeparableSettings, Error> {
    let s = SeparableSettings {
        kernel: o.get::<KernelMethod>(&OPTIONS, "kernel")?,
        taps: o.get(&OPTIONS, "taps")?,
        importance: !o.flag("uniform-taps"),
        k: o.get(&OPTIONS, "k")?,
        jitter: o.get(&OPTIONS, "jitter")?,
    };
    s.check()?;
    Ok(s)
}

/// The `separable` integrator and its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Separable {
    /// The kernel and filter.
    pub kernel: SeparableSettings,
    /// Light samples per quad or environment light when gathering each pixel's irradiance.
    pub light_samples: u32,
}

impl Default for Separable {
    fn default() -> Self {
        Separable {
            kernel: SeparableSettings::default(),
            light_samples: IrradianceSettings::default().light_samples,
        }
    }
}

impl Separable {
    /// The settings `options` describe.
    pub fn from_options(o: &MethodOptions) -> Result<Self, Error> {
        Ok(Separable {
            kernel: kernel_settings(o)?,
            ..Separable::default()
        })
    }
}

/// Names of the screen-space input layers (what `sss filter` reads back).
pub const LAYERS: [&str; 2] = ["irradiance", "surface"];

impl Integrator for Separable {
    fn name(&self) -> &'static str {
        METHOD.name
    }

    fn describe(&self) -> String {
        let s = &self.kernel;
        format!(
            "kernel {}, {} {} taps per pass, jitter {}",
            s.kernel,
            s.taps,
            if s.importance {
                "importance-sampled"
            } else {
                "uniform"
            },
            s.jitter
        )
    }

    fn layer_names(&self) -> &'static [&'static str] {
        &LAYERS
    }

    fn integrate(&self, frame: &Frame<'_>, progress: &dyn Progress) -> Result<Shaded, Error> {
        super::check_no_drift(frame, METHOD.name)?;
        let scene = frame.scene;
        // Fresnel-transmitted, textured irradiance at every translucent pixel sample.
        let irradiance: Vec<Rgb> = frame.timed("irradiance", || {
            frame
                .gbuffer
                .samples
                .par_iter()
                .enumerate()
                .with_min_len(PIXELS_PER_TASK / 4)
                // One light-packet buffer per task, cleared per sample.
                .map_init(Vec::new, |packets, (k, g)| {
                    let Some(sh) = frame.shading_of(g.object) else {
                        return [0.0; 3];
                    };
                    let mut r = rng(frame.seed, Stream::Irradiance, (1u64 << 62) ^ k as u64);
                    packets.clear();
                    let at = Receiver {
                        p: g.p,
                        n: g.n,
                        ng: g.ng,
                    };
                    gather(
                        &frame.geom,
                        &scene.lights,
                        at,
                        self.light_samples,
                        &mut r,
                        packets,
                    );
                    if let Some(c) = &sh.collision {
                        c.scale_entering(&frame.geom, g.object, (g.p, g.n, g.ng), packets);
                    }
                    sh.weights.entering(packets, g.n, sh.texture_at(g.p))
                })
                .collect()
        });
        // One kernel per material in use.
        let kernels = frame.timed("kernels", || -> Result<Vec<_>, Error> {
            let mut kernels: Vec<Option<MaterialKernel>> = Vec::new();
            for (m, sh) in frame.shading.iter().enumerate() {
                kernels.push(match sh {
                    Some(sh) => Some(build_kernel(sh.bssrdf(), &self.kernel).map_err(|e| {
                        Error::Input(format!(
                            "material `{}`: cannot build the {} kernel: {e}",
                            scene.materials[m].name, self.kernel.kernel
                        ))
                    })?),
                    None => None,
                });
            }
            Ok(kernels)
        })?;
        // Filter each material's pixels.
        let t = std::time::Instant::now();
        let gb = &frame.gbuffer;
        let (w, h) = (gb.width as usize, gb.height as usize);
        let screen = screen_buffers(frame, &irradiance);
        let mut values = vec![[0.0; 3]; gb.samples.len()];
        let opts = filter_options(&self.kernel, frame.seed);
        let mut taps = 0usize;
        for (m, kernel) in kernels.iter().enumerate() {
            let (Some(kernel), Some(sh)) = (kernel, frame.shading[m].as_ref()) else {
                continue;
            };
            let buffers = screen.material_input(scene, m, sh.units_per_mm, w, h);
            let input = buffers.input();
            let pixels = buffers.mask.iter().filter(|&&o| o != NO_OBJECT).count();
            let filtered = match kernel {
                MaterialKernel::Separable(k) => {
                    taps += pixels * k.taps_per_pixel();
                    screen_space::filter(&input, k, &opts)
                }
                MaterialKernel::Full(k2) => {
                    taps += pixels * k2.cells * k2.cells;
                    convolve2d::exact(&input, k2, &opts)
                }
            }
            .map_err(|e| Error::Input(format!("separable filter: {e}")))?;
            values
                .par_iter_mut()
                .zip(gb.samples.par_iter())
                .with_min_len(PIXELS_PER_TASK)
                .for_each(|(value, g)| {
                    if scene.objects[g.object as usize].material != m
                        || screen.object[g.pixel as usize] != g.object
                    {
                        return;
                    }
                    let f = filtered[g.pixel as usize];
                    let s = sh.exit_weights(g.n, g.wo);
                    *value = [f[0] as f64 * s[0], f[1] as f64 * s[1], f[2] as f64 * s[2]];
                });
        }
        progress.advance(gb.samples.len() as u64);
        frame.record("shading", t.elapsed().as_secs_f64());
        Ok(Shaded {
            values,
            std_error: None,
            stats: vec![Stat {
                name: "taps",
                value: taps as f64,
            }],
            layers: screen.layers(),
        })
    }
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

impl ScreenBuffers {
    /// As EXR layers ([`LAYERS`]): `irradiance`, and `surface` = (depth, footprint, object id
    /// + 1 with 0 for none; EXR values are kept non-negative).
    pub fn layers(&self) -> Vec<Layer> {
        let surface: Vec<Rgb> = (0..self.depth.len())
            .into_par_iter()
            .with_min_len(PIXELS_PER_TASK)
            .map(|i| {
                let id = if self.object[i] == u32::MAX {
                    0.0
                } else {
                    self.object[i] as f64 + 1.0
                };
                [self.depth[i], self.footprint[i], id]
            })
            .collect();
        vec![
            Layer {
                name: LAYERS[0],
                pixels: self.irradiance.clone(),
            },
            Layer {
                name: LAYERS[1],
                pixels: surface,
            },
        ]
    }
}

/// One material's screen-space inputs in mm, as `sss_separable::screen_space` takes them.
#[derive(Clone, Debug)]
pub struct MaterialInput {
    /// Image width (pixels).
    pub width: usize,
    /// Image height (pixels).
    pub height: usize,
    /// Irradiance of the material's pixels, 0 elsewhere.
    pub irradiance: Vec<[f32; 3]>,
    /// Distance from the camera (mm).
    pub depth: Vec<f32>,
    /// Object id of the material's pixels, [`NO_OBJECT`] elsewhere.
    pub mask: Vec<u32>,
    /// Pixel footprint (mm).
    pub mm_per_pixel: Vec<f32>,
}

impl MaterialInput {
    /// The buffers as the filter's input.
    pub fn input(&self) -> ScreenInput<'_> {
        ScreenInput {
            width: self.width,
            height: self.height,
            irradiance: &self.irradiance,
            depth: &self.depth,
            mask: &self.mask,
            mm_per_pixel: &self.mm_per_pixel,
        }
    }
}

impl ScreenBuffers {
    /// The pixels of `scene`'s material `material` (of a `width` × `height` image), converted
    /// from scene units to mm with `units_per_mm`; every other pixel is background.
    pub fn material_input(
        &self,
        scene: &Scene,
        material: usize,
        units_per_mm: f64,
        width: usize,
        height: usize,
    ) -> MaterialInput {
        let n = width * height;
        let mut b = MaterialInput {
            width,
            height,
            irradiance: vec![[0.0; 3]; n],
            depth: vec![0.0; n],
            mask: vec![NO_OBJECT; n],
            mm_per_pixel: vec![0.0; n],
        };
        b.irradiance
            .par_iter_mut()
            .zip(b.depth.par_iter_mut())
            .zip(b.mask.par_iter_mut())
            .zip(b.mm_per_pixel.par_iter_mut())
            .enumerate()
            .with_min_len(PIXELS_PER_TASK)
            .for_each(|(i, (((e, depth), mask), mm))| {
                let o = self.object[i];
                if o == NO_OBJECT || scene.objects[o as usize].material != material {
                    return;
                }
                *mask = o;
                *depth = (self.depth[i] / units_per_mm) as f32;
                *mm = (self.footprint[i] / units_per_mm) as f32;
                *e = self.irradiance[i].map(|v| v as f32);
            });
        b
    }
}

/// Per pixel: the first translucent sample's object, and the average irradiance, depth and
/// footprint of the pixel's samples on that object.
pub fn screen_buffers(frame: &Frame<'_>, irradiance: &[Rgb]) -> ScreenBuffers {
    let gb = &frame.gbuffer;
    let n = gb.pixels();
    let mut b = ScreenBuffers {
        irradiance: vec![[0.0; 3]; n],
        depth: vec![0.0; n],
        footprint: vec![0.0; n],
        object: vec![u32::MAX; n],
    };
    b.irradiance
        .par_iter_mut()
        .zip(b.depth.par_iter_mut())
        .zip(b.footprint.par_iter_mut())
        .zip(b.object.par_iter_mut())
        .enumerate()
        .with_min_len(PIXELS_PER_TASK)
        .for_each(|(i, (((irr, depth), footprint), object))| {
            let range = gb.offsets[i] as usize..gb.offsets[i + 1] as usize;
            let Some(first) = range
                .clone()
                .find(|&k| frame.shading_of(gb.samples[k].object).is_some())
            else {
                return;
            };
            let o = gb.samples[first].object;
            let mut count = 0.0;
            for k in range {
                let g = &gb.samples[k];
                if g.object != o {
                    continue;
                }
                for c in 0..3 {
                    irr[c] += irradiance[k][c];
                }
                *depth += g.distance;
                *footprint += g.footprint;
                count += 1.0;
            }
            *object = o;
            *irr = irr.map(|v| v / count);
            *depth /= count;
            *footprint /= count;
        });
    b
}
