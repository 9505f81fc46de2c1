//! Irradiance samples (Jensen & Buhler 2002, the first pass of every point-based method):
//! blue-noise points on each translucent object separately, each with its area and the
//! irradiance transmitted through the surface from all lights, shadow rays included.
//!
//! Spacing follows the material: `spacing_mfp` times the smallest reduced mean free path
//! 1/σ'_t over the channels (in scene units), bounded by a per-object cap on the count. Only
//! the objects the caller lists get samples (the renderer passes the translucent objects the
//! camera sees), and with [`compute_for`] only the part of each object within the profile's
//! reach of a point that will be shaded: a sample farther than the radius holding all but
//! [`REACH_LEFT_OUT`] of the diffuse reflectance ([`Bssrdf::radius_for_energy`], largest over
//! the channels) from every shaded point adds less than that fraction of what it would add
//! beside one, so a large object seen close up is sampled where it is seen, at the spacing
//! asked for, instead of all over at a spacing the per-object cap coarsens. For the
//! directional dipole, whose S depends on the incident direction, and for a drifting material
//! (`drift = true`, whose light leaves ahead of its direction), each sample also keeps its
//! incident light packets.
//!
//! [`Bssrdf::radius_for_energy`]: sss_bssrdf::Bssrdf::radius_for_energy

use crate::geometry::{SceneGeometry, triangles_of};
use crate::lights::{Incident, Receiver, gather};
use crate::rng::{Stream, rng};
use crate::shading::BoundaryWeights;
use glam::DVec3;
use rayon::prelude::*;
use sss_bssrdf::{ModelKind, Rgb};
use sss_scene::Scene;
use std::collections::HashMap;

/// How densely to sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrradianceSettings {
    /// Minimum spacing in units of the material's smallest reduced mean free path.
    pub spacing_mfp: f64,
    /// At most this many samples per object (the spacing grows to respect it).
    pub max_samples: usize,
    /// Light samples per quad or environment light at each irradiance sample.
    pub light_samples: u32,
    /// Bounces of the light the surfaces trade, added to the direct light by the point sums
    /// (`crate::integrators::point_sums::lit_samples`; 0: direct light only). [`compute`]
    /// lights the samples directly whatever this says.
    pub bounces: u32,
}

impl Default for IrradianceSettings {
    /// The declared defaults of `--spacing`, `--max-samples` and `--bounces`
    /// ([`crate::integrators::options::SAMPLE_OPTIONS`]), 16 light samples.
    fn default() -> Self {
        use crate::integrators::options::{SAMPLE_OPTIONS, declared};
        IrradianceSettings {
            spacing_mfp: declared(&SAMPLE_OPTIONS, "spacing"),
            max_samples: declared(&SAMPLE_OPTIONS, "max-samples"),
            light_samples: 16,
            bounces: declared(&SAMPLE_OPTIONS, "bounces"),
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
    /// Directional-dipole and drifting objects only (`drift = true`): every sample's incident
    /// light packets (texture applied, no Fresnel factor),
    /// `incident[incident_offsets[i]..incident_offsets[i + 1]]` for sample i. Empty for the
    /// others.
    pub incident: Vec<Incident>,
    /// Offsets into `incident` (length samples + 1), or empty.
    pub incident_offsets: Vec<u32>,
    /// About how many samples at the spacing used were left out as out of reach of every
    /// shaded point ([`compute_for`]): the samples' count scaled by the area left out over
    /// the area sampled. 0 when the whole object was sampled.
    pub left_out: usize,
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

/// The fraction of a profile's diffuse reflectance beyond the reach within which
/// [`compute_for`] samples an object.
pub const REACH_LEFT_OUT: f64 = 1e-6;

/// Places and lights the samples of each object in `objects` (all must be translucent), all
/// over each object.
pub fn compute(
    scene: &Scene,
    geom: &SceneGeometry,
    objects: &[u32],
    settings: &IrradianceSettings,
    seed: u64,
) -> Vec<ObjectSamples> {
    compute_within(scene, geom, objects, settings, seed, None)
}

/// The points of one object that will be shaded, and its profile's reach ([`reach`]).
#[derive(Clone, Debug, Default)]
pub struct ShadedPoints {
    /// Positions (scene units).
    pub points: Vec<DVec3>,
    /// The distance (scene units) beyond which a sample is left out; infinite: none is.
    pub reach: f64,
}

/// [`compute`] for the points that will be shaded, `shaded[k]` on `objects[k]`: each object is
/// sampled only where it lies within its profile's reach of one of them (see the [module
/// docs](self)); [`ObjectSamples::left_out`] says about how many samples that saved.
pub fn compute_for(
    scene: &Scene,
    geom: &SceneGeometry,
    objects: &[u32],
    settings: &IrradianceSettings,
    seed: u64,
    shaded: &[ShadedPoints],
) -> Vec<ObjectSamples> {
    compute_within(scene, geom, objects, settings, seed, Some(shaded))
}

/// The radius (scene units) holding all but [`REACH_LEFT_OUT`] of `model`'s diffuse
/// reflectance in every channel, for a material of `units_per_mm` scene units per mm;
/// infinite when the model gives no finite positive radius.
pub fn reach(model: &dyn sss_bssrdf::Bssrdf, units_per_mm: f64) -> f64 {
    let mut r: f64 = 0.0;
    for c in 0..3 {
        let v = model.radius_for_energy(c, 1.0 - REACH_LEFT_OUT);
        if !(v.is_finite() && v > 0.0) {
            return f64::INFINITY;
        }
        r = r.max(v);
    }
    let r = r * units_per_mm;
    if r.is_finite() && r > 0.0 {
        r
    } else {
        f64::INFINITY
    }
}

/// The indices of the triangles of `tris` within `radius` of a point of `points`, taken
/// conservatively (a triangle is kept when a point lies in its bounding box grown by
/// `radius`), through a sparse grid of cells of side `radius` over the points.
fn within_reach(tris: &[[DVec3; 3]], points: &[DVec3], radius: f64) -> Vec<u32> {
    let cell = |p: DVec3| -> [i64; 3] {
        let q = (p / radius).floor();
        [q.x as i64, q.y as i64, q.z as i64]
    };
    let mut grid: HashMap<[i64; 3], Vec<DVec3>> = HashMap::new();
    for &p in points.iter().filter(|p| p.is_finite()) {
        grid.entry(cell(p)).or_default().push(p);
    }
    let count = grid.values().map(Vec::len).sum::<usize>();
    (0..tris.len() as u32)
        .into_par_iter()
        .filter(|&t| {
            let [a, b, c] = tris[t as usize];
            let lo = a.min(b).min(c) - DVec3::splat(radius);
            let hi = a.max(b).max(c) + DVec3::splat(radius);
            if !(lo.is_finite() && hi.is_finite()) {
                return false;
            }
            let inside = |p: &DVec3| p.cmpge(lo).all() && p.cmple(hi).all();
            let (cl, ch) = (cell(lo), cell(hi));
            let cells = (0..3).fold(1u128, |n, k| n * (ch[k] - cl[k] + 1).max(0) as u128);
            if cells > count as u128 {
                return grid.values().flatten().any(inside);
            }
            for x in cl[0]..=ch[0] {
                for y in cl[1]..=ch[1] {
                    for z in cl[2]..=ch[2] {
                        if grid.get(&[x, y, z]).is_some_and(|ps| ps.iter().any(inside)) {
                            return true;
                        }
                    }
                }
            }
            false
        })
        .collect()
}

fn compute_within(
    scene: &Scene,
    geom: &SceneGeometry,
    objects: &[u32],
    settings: &IrradianceSettings,
    seed: u64,
    shaded: Option<&[ShadedPoints]>,
) -> Vec<ObjectSamples> {
    objects
        .iter()
        .enumerate()
        .filter_map(|(k, &o)| {
            let mat = scene.translucent(o as usize)?;
            let medium = &mat.medium;
            let mfp_mm = (0..3)
                .map(|c| 1.0 / medium.sigma_t_reduced(c).max(1e-300))
                .fold(f64::INFINITY, f64::min);
            let spacing = settings.spacing_mfp * mfp_mm * mat.units_per_mm;
            let mesh = geom.mesh(o);
            let all = triangles_of(mesh);
            // The triangles sampled (indices into the mesh's), and the whole mesh's area when
            // some were left out (the sampled area is the placement's).
            let (kept, whole_area) = match shaded.and_then(|s| s.get(k)) {
                Some(s) if s.reach.is_finite() => {
                    let area = |t: &[DVec3; 3]| 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length();
                    let whole: f64 = all.iter().map(area).filter(|a| a.is_finite()).sum();
                    (within_reach(&all, &s.points, s.reach), Some(whole))
                }
                _ => ((0..all.len() as u32).collect(), None),
            };
            let tris: Vec<[DVec3; 3]> = kept.iter().map(|&t| all[t as usize]).collect();
            let place_seed = sss_util::splitmix64(
                seed ^ sss_util::splitmix64(Stream::Placement as u64 + o as u64),
            );
            let (points, stats) =
                sss_hierarchy::blue_noise_on_mesh(&tris, spacing, settings.max_samples, place_seed);
            let left_out = match whole_area {
                Some(whole) if whole > stats.surface_area && stats.surface_area > 0.0 => {
                    (points.len() as f64 * (whole - stats.surface_area) / stats.surface_area)
                        .round() as usize
                }
                _ => 0,
            };
            // The directional dipole and a drifting model need each packet's direction.
            let directional = mat.model == ModelKind::DirectionalDipole || mat.drift;
            let weights = BoundaryWeights::of(mat);
            // `unscattered = true`: only the share of each packet that scatters enters the
            // profile.
            let collision = crate::unscattered::Collision::of(mat);
            let lit: Vec<(IrradianceSample, Vec<Incident>)> = points
                .par_iter()
                .enumerate()
                .map(|(i, s)| {
                    let [a, b, c] = mesh.triangles[kept[s.triangle as usize] as usize];
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
                    if let Some(c) = &collision {
                        c.scale_entering(geom, o, (s.position, n, ng), &mut inc);
                    }
                    let e = weights.entering(&mut inc, n, tex);
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
                left_out,
            })
        })
        .collect()
}
