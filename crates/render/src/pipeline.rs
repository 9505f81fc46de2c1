//! One render: scene → [`Frame`] (BVHs, G-buffer, models of the translucent objects the camera
//! sees) → an [`Integrator`] → the subsurface image, the total image (opaque surfaces lit
//! directly, the background) and timings by stage.

use crate::frame::Frame;
use crate::frame::pixel_value;
pub use crate::frame::{Stage, assembled_subsurface};
use crate::integrators::{Integrator, Layer, Stat};
use crate::lights::background;
use crate::progress::Progress;
use rayon::prelude::*;
use sss_bssrdf::Rgb;
use sss_scene::Scene;
use std::time::Instant;

/// What a render needs besides the scene and the integrator.
#[derive(Clone, Debug, PartialEq)]
pub struct RenderSettings {
    /// Seed of every random stream.
    pub seed: u64,
    /// Light samples per quad or environment light when shading opaque surfaces.
    pub opaque_light_samples: u32,
    /// Memory budget in bytes: a frame estimated to need more is refused before anything is
    /// allocated ([`crate::budget::check_frame`]). Default: half the physical memory.
    pub max_memory: u64,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            seed: 1,
            opaque_light_samples: 16,
            max_memory: crate::budget::default_budget(),
        }
    }
}

/// The result of a render. Pixel arrays are row-major from the top-left, width·height long,
/// linear RGB, finite and non-negative.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// The integrator's name.
    pub method: &'static str,
    /// Image width.
    pub width: u32,
    /// Image height.
    pub height: u32,
    /// The subsurface term (0 off translucent objects).
    pub subsurface: Vec<Rgb>,
    /// Subsurface on translucent objects, direct diffuse light on opaque ones, the environment
    /// where rays leave the scene.
    pub total: Vec<Rgb>,
    /// Stochastic methods: the standard error of each pixel's subsurface estimate.
    pub std_error: Option<Vec<Rgb>>,
    /// Fraction of each pixel's camera samples that landed on a translucent object.
    pub coverage: Vec<f32>,
    /// Fraction of each pixel's camera samples that landed on any object (the film's alpha,
    /// as other renderers write it: 1 inside silhouettes, 0 on the background, fractions on
    /// edges).
    pub alpha: Vec<f32>,
    /// Timings by stage, in order.
    pub stages: Vec<Stage>,
    /// The method's own statistics.
    pub stats: Vec<Stat>,
    /// Irradiance samples built, summed over objects (0 when the method used none).
    pub irradiance_samples: usize,
    /// About how many more irradiance samples the whole objects would have needed at the
    /// spacing used: the parts out of the profile's reach of every visible point, left out.
    pub irradiance_left_out: usize,
    /// Minimum spacing of the irradiance samples per object (object index, scene units).
    pub spacing: Vec<(u32, f64)>,
    /// Extra per-pixel layers of the method (e.g. the separable pass's screen-space inputs).
    pub layers: Vec<Layer>,
    /// Warnings for the user: caps that bound (with the requested and effective value and how
    /// to lift them), implausible units. Empty when nothing needs saying.
    pub warnings: Vec<String>,
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

    /// The extra layer named `name`, if the method produced it.
    pub fn layer(&self, name: &str) -> Option<&[Rgb]> {
        self.layers
            .iter()
            .find(|l| l.name == name)
            .map(|l| l.pixels.as_slice())
    }
}

/// Renders `scene` with `integrator`. `progress` counts shaded G-buffer samples. Fails before
/// allocating when the scene breaks the invariants of its types ([`check_scene`]) or the frame
/// with the method's irradiance samples and structures ([`Integrator::structure_bytes`]) would
/// not fit `settings.max_memory`, and when the integrator fails (e.g. a kernel cannot be
/// built, or a method needs a radial model).
pub fn render(
    scene: &Scene,
    integrator: &dyn Integrator,
    settings: &RenderSettings,
    progress: &dyn Progress,
) -> Result<RenderOutput, crate::Error> {
    check_scene(scene)?;
    crate::budget::check_frame(scene, settings.max_memory)?;
    if let Some(irradiance) = integrator.irradiance_settings() {
        crate::budget::check_irradiance_with(
            scene,
            &irradiance,
            |est| integrator.structure_bytes(scene, est),
            settings.max_memory,
        )?;
    } else {
        crate::budget::check_structures(
            scene,
            integrator.name(),
            integrator.structure_bytes(scene, &[]),
            settings.max_memory,
        )?;
    }
    let frame = Frame::prepare(scene, settings.seed);
    progress.start(frame.gbuffer.samples.len() as u64);
    let mut shaded = integrator.integrate(&frame, progress)?;
    if shaded.values.len() != frame.gbuffer.samples.len() {
        return Err(crate::Error::Input(format!(
            "internal: method {} returned {} values for {} G-buffer samples",
            integrator.name(),
            shaded.values.len(),
            frame.gbuffer.samples.len()
        )));
    }
    // The light refracted through the objects without a collision, and the share of the
    // model's light that scattered along each camera ray (`unscattered = true`). A method's
    // standard errors are left as they are: the share is at most 1, so they stay an upper
    // bound.
    if !integrator.follows_media() && crate::unscattered::wanted(scene) {
        let split = frame.timed("unscattered", || crate::unscattered::split(&frame));
        for ((v, u), k) in shaded
            .values
            .iter_mut()
            .zip(&split.light)
            .zip(&split.leaving)
        {
            for c in 0..3 {
                v[c] = v[c] * k[c] + u[c];
            }
        }
        shaded.stats.push(Stat {
            name: "unscattered_rays",
            value: split.counts.rays as f64,
        });
        shaded.stats.push(Stat {
            name: "unscattered_parts_cut",
            value: split.counts.cut as f64,
        });
    }
    let (irradiance_samples, spacing) = frame.samples_built();
    let irradiance_left_out = frame.samples_left_out();
    let (subsurface, total, coverage, alpha) = assemble(&frame, &shaded.values, settings);
    Ok(RenderOutput {
        method: integrator.name(),
        width: frame.gbuffer.width,
        height: frame.gbuffer.height,
        subsurface,
        total,
        std_error: shaded.std_error,
        coverage,
        alpha,
        stages: frame.stages(),
        stats: shaded.stats,
        irradiance_samples,
        irradiance_left_out,
        spacing,
        layers: shaded.layers,
        warnings: frame.warnings(),
    })
}

/// Largest accepted deviation of a shading normal's length from 1.
const UNIT_TOLERANCE: f64 = 1e-6;

/// Checks what [`sss_scene::load`] guarantees, for scenes built or edited in code: every light
/// has finite geometry and finite, non-negative emission (a directional light a unit
/// direction, a quad light non-parallel edges); every object names an existing material, and
/// its mesh has finite positions, one finite unit normal per position, triangles that index
/// existing vertices and at least one triangle of non-zero area (degenerate triangles among
/// others are tolerated: they have no area to be hit or sampled). A NaN normal or light would otherwise shade as
/// NaN (and be counted as black), an index past the vertices would panic. Returns an
/// [`Error::Input`](crate::Error::Input) naming the light or object and the problem.
pub fn check_scene(scene: &Scene) -> Result<(), crate::Error> {
    use sss_scene::Light;
    for (i, l) in scene.lights.iter().enumerate() {
        let (emission, vectors, problem) = match l {
            Light::Point {
                position,
                intensity,
            } => (intensity, vec![*position], None),
            Light::Directional {
                direction,
                irradiance,
            } => (
                irradiance,
                vec![*direction],
                ((direction.length() - 1.0).abs() > UNIT_TOLERANCE)
                    .then_some("the direction is not a unit vector"),
            ),
            Light::Sun {
                direction,
                irradiance,
                half_angle,
            } => (
                irradiance,
                vec![*direction],
                if (direction.length() - 1.0).abs() > UNIT_TOLERANCE {
                    Some("the direction is not a unit vector")
                } else if crate::lights::sun_radiance(*irradiance, *half_angle).is_none() {
                    Some("the half angle is not in (0, π/2]")
                } else {
                    None
                },
            ),
            Light::Quad {
                corner,
                edge_u,
                edge_v,
                radiance,
            } => (
                radiance,
                vec![*corner, *edge_u, *edge_v],
                (edge_u.cross(*edge_v).length() <= 1e-12 * edge_u.length() * edge_v.length())
                    .then_some("the edges are parallel or zero, so the quad has no area"),
            ),
            Light::Environment { radiance } => (radiance, vec![], None),
        };
        let problem = if vectors.iter().any(|v| !v.is_finite()) {
            Some("a position or direction is not finite")
        } else if emission.iter().any(|e| !(e.is_finite() && *e >= 0.0)) {
            Some("the emission must be finite and non-negative")
        } else {
            problem
        };
        if let Some(p) = problem {
            return Err(crate::Error::Input(format!(
                "light {i} of scene `{}`: {p} ({l:?})",
                scene.name
            )));
        }
    }
    for (i, o) in scene.objects.iter().enumerate() {
        let fail = |what: String| {
            Err(crate::Error::Input(format!(
                "object {i} (`{}`) of scene `{}`: {what}",
                o.name, scene.name
            )))
        };
        if o.material >= scene.materials.len() {
            return fail(format!(
                "material index {} is out of range ({} materials)",
                o.material,
                scene.materials.len()
            ));
        }
        let m = &o.mesh;
        if m.triangles.is_empty() {
            return fail("the mesh has no triangles".into());
        }
        if let Some(k) = m.positions.iter().position(|p| !p.is_finite()) {
            return fail(format!(
                "vertex position {k} is not finite: {}",
                m.positions[k]
            ));
        }
        if m.normals.len() != m.positions.len() {
            return fail(format!(
                "the mesh has {} normals for {} positions (one per position needed)",
                m.normals.len(),
                m.positions.len()
            ));
        }
        if let Some(k) = m
            .normals
            .iter()
            .position(|n| !(n.is_finite() && (n.length() - 1.0).abs() <= UNIT_TOLERANCE))
        {
            return fail(format!(
                "vertex normal {k} is not a finite unit vector: {}",
                m.normals[k]
            ));
        }
        let n = m.positions.len();
        if let Some(t) = m
            .triangles
            .iter()
            .position(|t| t.iter().any(|&v| v as usize >= n))
        {
            return fail(format!(
                "triangle {t} {:?} names a vertex past the {n} positions",
                m.triangles[t]
            ));
        }
        let has_area = m.triangles.iter().any(|t| {
            let [a, b, c] = t.map(|v| m.positions[v as usize]);
            (b - a).cross(c - a).length_squared() > 0.0
        });
        if !has_area {
            return fail(format!(
                "the mesh has no triangle with non-zero area (all {} repeat a vertex or are \
                 collinear)",
                m.triangles.len()
            ));
        }
    }
    Ok(())
}

/// Per pixel, from per-G-buffer-sample subsurface values: the subsurface image, the total
/// (opaque samples shaded, the background added for camera samples that missed) and the
/// translucent coverage and the coverage by any object (alpha). Non-finite or negative values
/// count as 0. Timed as stage `opaque`.
fn assemble(
    frame: &Frame<'_>,
    subsurface: &[Rgb],
    settings: &RenderSettings,
) -> (Vec<Rgb>, Vec<Rgb>, Vec<f32>, Vec<f32>) {
    let gb = &frame.gbuffer;
    let spp = gb.samples_per_pixel as f64;
    let bg = background(&frame.scene.lights);
    let t = Instant::now();
    let n = gb.pixels();
    let mut subsurface_px = vec![[0.0; 3]; n];
    let mut total_px = vec![[0.0; 3]; n];
    let mut coverage = vec![0.0f32; n];
    let mut alpha = vec![0.0f32; n];
    subsurface_px
        .par_iter_mut()
        .zip(total_px.par_iter_mut())
        .zip(coverage.par_iter_mut())
        .zip(alpha.par_iter_mut())
        .enumerate()
        .with_min_len(1024)
        // One light-packet buffer per task for the opaque samples.
        .for_each_init(Vec::new, |packets, (i, (((sss, total), cov), a))| {
            let (lo, hi) = (gb.offsets[i] as usize, gb.offsets[i + 1] as usize);
            let mut covered = 0u32;
            for k in lo..hi {
                let g = &gb.samples[k];
                let translucent = frame.shading_of(g.object).is_some();
                let v = if translucent {
                    covered += 1;
                    subsurface[k]
                } else {
                    frame.shade_opaque_with(g, settings.opaque_light_samples, packets)
                };
                for c in 0..3 {
                    let v = pixel_value(v[c]);
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
            *cov = covered as f32 / spp as f32;
            *a = (hi - lo) as f32 / spp as f32;
        });
    frame.record("opaque", t.elapsed().as_secs_f64());
    (subsurface_px, total_px, coverage, alpha)
}
