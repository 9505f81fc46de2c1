//! Irradiance samples (Jensen & Buhler 2002, the first pass of every point-based method):
//! blue-noise points on each translucent object separately, each with its area and the
//! irradiance transmitted through the surface from all lights, shadow rays included.
//!
//! Spacing follows the material: `spacing_mfp` times the smallest reduced mean free path
//! 1/σ'_t over the channels (in scene units), bounded by a per-object cap on the count. Only
//! the objects the caller lists get samples (the renderer passes the translucent objects the
//! camera sees). For the directional dipole, whose S depends on the incident direction, each
//! sample also keeps its incident light packets.

use crate::geometry::{SceneGeometry, triangles_of};
use crate::lights::{Incident, Receiver, gather};
use crate::rng::{Stream, rng};
use crate::shading::transmitted_irradiance;
use glam::DVec3;
use rayon::prelude::*;
use sss_bssrdf::{ModelKind, Rgb};
use sss_scene::Scene;

/// How densely to sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrradianceSettings {
    /// Minimum spacing in units of the material's smallest reduced mean free path.
    pub spacing_mfp: f64,
    /// At most this many samples per object (the spacing grows to respect it).
    pub max_samples: usize,
    /// Light samples per quad or environment light at each irradiance sample.
    pub light_samples: u32,
}

impl Default for IrradianceSettings {
    fn default() -> Self {
        IrradianceSettings {
            spacing_mfp: 0.5,
            max_samples: 100_000,
            light_samples: 16,
        }
    }
}

/// One irradiance sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrradianceSample {
    /// Position on the surface.
    pub position: DVec3,
    /// Unit shading normal (out of the object).
    pub normal: DVec3,
    /// Surface area it stands for (scene units²); the areas of an object sum to its area.
    pub area: f64,
    /// Irradiance transmitted into the medium, Σ F_t(η, cos θ) E, times the material's
    /// pre-scatter texture.
    pub irradiance: Rgb,
}

/// The samples of one object.
#[derive(Clone, Debug)]
pub struct ObjectSamples {
    /// Object index.
    pub object: u32,
    /// Minimum spacing actually used (scene units).
    pub spacing: f64,
    /// The smallest reduced mean free path of the object's material (scene units).
    pub mfp: f64,
    /// The samples.
    pub samples: Vec<IrradianceSample>,
    /// Directional-dipole objects only: every sample's incident light packets (texture
    /// applied, no Fresnel factor), `incident[incident_offsets[i]..incident_offsets[i + 1]]`
    /// for sample i. Empty for separable models.
    pub incident: Vec<Incident>,
    /// Offsets into `incident` (length samples + 1), or empty.
    pub incident_offsets: Vec<u32>,
}

impl ObjectSamples {
    /// The minimum spacing `settings` asked for (scene units): `spacing_mfp` × the smallest
    /// reduced mean free path.
    pub fn requested_spacing(&self, settings: &IrradianceSettings) -> f64 {
        settings.spacing_mfp * self.mfp
    }

    /// Whether the per-object cap (`max_samples`) made the samples coarser than `settings`
    /// asked for.
    pub fn capped(&self, settings: &IrradianceSettings) -> bool {
        self.spacing > self.requested_spacing(settings) * (1.0 + 1e-9)
    }

    /// The incident light packets of sample `i` (empty unless the model needs directions).
    pub fn incident_of(&self, i: usize) -> &[Incident] {
        if self.incident_offsets.is_empty() {
            return &[];
        }
        &self.incident[self.incident_offsets[i] as usize..self.incident_offsets[i + 1] as usize]
    }
}

/// Places and lights the samples of each object in `objects` (all must be translucent).
pub fn compute(
    scene: &Scene,
    geom: &SceneGeometry,
    objects: &[u32],
    settings: &IrradianceSettings,
    seed: u64,
) -> Vec<ObjectSamples> {
    objects
        .iter()
        .filter_map(|&o| {
            let mat = scene.translucent(o as usize)?;
            let medium = &mat.medium;
            let mfp_mm = (0..3)
                .map(|c| 1.0 / medium.sigma_t_reduced(c).max(1e-300))
                .fold(f64::INFINITY, f64::min);
            let spacing = settings.spacing_mfp * mfp_mm * mat.units_per_mm;
            let mesh = geom.mesh(o);
            let tris = triangles_of(mesh);
            let place_seed = sss_util::splitmix64(
                seed ^ sss_util::splitmix64(Stream::Placement as u64 + o as u64),
            );
            let (points, stats) =
                sss_hierarchy::blue_noise_on_mesh(&tris, spacing, settings.max_samples, place_seed);
            let directional = mat.model == ModelKind::DirectionalDipole;
            let eta = medium.eta();
            let lit: Vec<(IrradianceSample, Vec<Incident>)> = points
                .par_iter()
                .enumerate()
                .map(|(i, s)| {
                    let [a, b, c] = mesh.triangles[s.triangle as usize];
                    let (pa, pb, pc) = (
                        mesh.positions[a as usize],
                        mesh.positions[b as usize],
                        mesh.positions[c as usize],
                    );
                    let ng = (pb - pa).cross(pc - pa).normalize_or_zero();
                    let w = 1.0 - s.u - s.v;
                    let n = (mesh.normals[a as usize] * w
                        + mesh.normals[b as usize] * s.u
                        + mesh.normals[c as usize] * s.v)
                        .normalize_or(ng);
                    let mut r = rng(seed, Stream::Irradiance, ((o as u64) << 40) ^ i as u64);
                    let mut inc = Vec::new();
                    gather(
                        geom,
                        &scene.lights,
                        Receiver {
                            p: s.position,
                            n,
                            ng,
                        },
                        settings.light_samples,
                        &mut r,
                        &mut inc,
                    );
                    let tex = mat
                        .texture
                        .as_ref()
                        .map_or([1.0; 3], |t| t.eval(s.position));
                    let e = transmitted_irradiance(&mut inc, n, eta, tex);
                    let sample = IrradianceSample {
                        position: s.position,
                        normal: n,
                        area: s.area,
                        irradiance: e,
                    };
                    (sample, if directional { inc } else { Vec::new() })
                })
                .collect();
            let mut samples = Vec::with_capacity(lit.len());
            let mut incident = Vec::new();
            let mut incident_offsets = Vec::new();
            if directional {
                incident_offsets.push(0);
            }
            for (s, inc) in lit {
                samples.push(s);
                if directional {
                    incident.extend(inc);
                    incident_offsets.push(incident.len() as u32);
                }
            }
            Some(ObjectSamples {
                object: o,
                spacing: stats.radius,
                mfp: mfp_mm * mat.units_per_mm,
                samples,
                incident,
                incident_offsets,
            })
        })
        .collect()
}
