//! Light the surfaces trade, gathered into the irradiance samples (`--bounces N`).
//!
//! A BSSRDF under direct light carries only the light that reaches a surface point straight
//! from the lights. Real transport also carries the light that left one part of a translucent
//! object and reaches another: a dragon's coils, the head's chin and shoulders, a fold of skin.
//! `volpath --reentry no` measures what that leaves out: 5–20 % of the image of the truth
//! experiment's meshes in marble, 2–14 % in skin1, nothing on a sphere.
//!
//! Each bounce is the gather of radiosity (Cohen & Wallace 1993, ch. 4; the irradiance
//! samples of Jensen & Buhler 2002 as its nodes): at every irradiance sample x_i,
//! [`BOUNCE_RAYS`] cosine-distributed rays about its normal. Where a ray meets the outside of
//! a translucent surface at y, the radiance coming back along it is the model's,
//! L = W_o(y, −ω) M(y), with M the point sum (before the exit weight) of the previous
//! bounce's samples, read at the sample of that object nearest y; plus the lights seen in the
//! mirror direction times F_r(η, cos θ_y), the smooth surface's reflection. Anything else, or
//! nothing, sends back nothing (the lights and the environment are the direct light's). Each
//! ray's L, weighted π/N (cosine-distributed sampling of E = ∫ L cos θ dω), enters through
//! the material's boundary weights as a direct packet would, so a sample's irradiance becomes
//! its direct irradiance plus this. N bounces repeat the gather with the exitance of the
//! previous one: the Neumann series of the light transport cut after N + 1 terms. M is the
//! single-tree traversal at ε = [`BOUNCE_EPS`], evaluated at one sample per leaf of the
//! illumination tree and given to the leaf's samples ([`super::ILLUMINATION_LEAF`], a few
//! spacings across, over which the exitance is smooth). Rays are seeded per sample and
//! bounce, so the image does not depend on the thread count.
//!
//! Left out: light reflected by opaque surfaces (the renderer lights them directly only, and
//! `volpath`, the truth this is measured against, ends its paths there too); light that
//! crosses a translucent object without scattering (the model has no unscattered light); and
//! the translucent objects the camera does not see, which have no samples (a ray that meets
//! one, or a part of a seen object that was not sampled, brings back nothing and is counted
//! in the stat `bounce_rays_unsampled`). Radial models only: the directional dipole and
//! drifting materials, whose samples keep their light's directions, are refused.

use super::{Counts, illumination_trees, single, tree_balls};
use crate::Error;
use crate::frame::Frame;
use crate::irradiance::ObjectSamples;
use crate::lights::Incident;
use crate::local_radius::FrameBalls;
use crate::rng::{Stream, rng};
use crate::volume::emitters::Emitters;
use glam::DVec3;
use rand::RngExt;
use rayon::prelude::*;
use sss_bssrdf::Rgb;
use sss_bssrdf::fresnel::fr_dielectric;
use sss_scene::MaterialKind;
use std::collections::HashMap;
use std::f64::consts::PI;
use std::sync::atomic::{AtomicU64, Ordering};

/// Rays per irradiance sample and bounce.
pub const BOUNCE_RAYS: u32 = 32;

/// The solid-angle threshold of the exitance evaluated at the samples for a bounce.
pub const BOUNCE_EPS: f64 = 0.2;

/// The gather's figures, (name, value): rays cast, and those that met a surface without
/// samples.
pub type Figures = Vec<(&'static str, f64)>;

/// The most bounces a render may ask for.
pub const MAX_BOUNCES: u32 = 8;

/// `direct` (the samples lit by the lights) lit also by `bounces` bounces of the light the
/// surfaces trade, and the stats of the gather. Errors name a material whose model the
/// bounce cannot sum (the directional dipole, drift).
pub(crate) fn bounced(
    frame: &Frame<'_>,
    direct: &[ObjectSamples],
    balls: &FrameBalls,
    bounces: u32,
) -> Result<(Vec<ObjectSamples>, Figures), Error> {
    for s in direct {
        if let Some(sh) = frame.shading_of(s.object)
            && (sh.directional() || sh.drift.is_some() || sh.local_drift)
        {
            return Err(Error::Unsupported(format!(
                "material `{}`: --bounces sums radial profiles only; its model keeps the \
                 light's directions (the directional dipole, or drift = true): use \
                 --bounces 0",
                sh.name
            )));
        }
    }
    let emitters = Emitters::new(&frame.scene.lights);
    // The samples' positions do not change from bounce to bounce: their lookups are built once,
    // over the direct set.
    let nearest: Vec<Option<Nearest>> = (0..frame.scene.objects.len() as u32)
        .map(|o| direct.iter().find(|s| s.object == o).map(Nearest::new))
        .collect();
    let by_object: Vec<Option<usize>> = (0..frame.scene.objects.len() as u32)
        .map(|o| direct.iter().position(|s| s.object == o))
        .collect();
    let weight = PI / f64::from(BOUNCE_RAYS);
    let mut lit: Vec<ObjectSamples> = direct.to_vec();
    let (rays, unsampled) = (AtomicU64::new(0), AtomicU64::new(0));
    for bounce in 0..bounces {
        let exitance = frame.timed("bounce_exitance", || {
            exitance_at_samples(frame, &lit, balls)
        });
        let gathered: Vec<Vec<Rgb>> = lit
            .iter()
            .map(|s| {
                let Some(sh) = frame.shading_of(s.object) else {
                    return vec![[0.0; 3]; s.samples.len()];
                };
                s.samples
                    .par_iter()
                    .enumerate()
                    .map_init(Vec::new, |packets, (i, p)| {
                        let index = ((s.object as u64) << 40) ^ ((bounce as u64) << 32) ^ i as u64;
                        let mut r = rng(frame.seed, Stream::Interreflection, index);
                        packets.clear();
                        for _ in 0..BOUNCE_RAYS {
                            let dir = cosine_about(p.normal, r.random(), r.random());
                            let l = radiance_along(
                                frame, &emitters, &exitance, &nearest, &by_object, p.position,
                                p.normal, dir, &unsampled,
                            );
                            packets.push(Incident {
                                dir,
                                e_cos: l.map(|v| v * weight),
                            });
                        }
                        rays.fetch_add(u64::from(BOUNCE_RAYS), Ordering::Relaxed);
                        sh.weights
                            .entering(packets, p.normal, sh.texture_at(p.position))
                    })
                    .collect()
            })
            .collect();
        for ((out, d), g) in lit.iter_mut().zip(direct).zip(&gathered) {
            for ((o, d), g) in out.samples.iter_mut().zip(&d.samples).zip(g) {
                o.irradiance = std::array::from_fn(|c| d.irradiance[c] + g[c]);
            }
        }
    }
    let figures = vec![
        ("bounce_rays", rays.load(Ordering::Relaxed) as f64),
        (
            "bounce_rays_unsampled",
            unsampled.load(Ordering::Relaxed) as f64,
        ),
    ];
    Ok((lit, figures))
}

/// Per object of `samples` (in its order), the point sum before the exit weight at each of
/// its samples: the single-tree traversal at [`BOUNCE_EPS`] (each pair with its own ball where
/// the material gives each point one), evaluated at one sample of each leaf of the
/// illumination tree (its first, [`super::ILLUMINATION_LEAF`] samples a few spacings across)
/// and given to the leaf's every sample: the exitance is smooth over a few sample spacings,
/// and this costs a leaf's share of the samples' traversals.
fn exitance_at_samples(
    frame: &Frame<'_>,
    samples: &[ObjectSamples],
    balls: &FrameBalls,
) -> Vec<Vec<Rgb>> {
    let trees = illumination_trees(frame, samples);
    let tree_balls = tree_balls(balls, &trees);
    let counts = Counts::default();
    samples
        .iter()
        .map(|s| {
            let mut out = vec![[0.0; 3]; s.samples.len()];
            let (Some(sh), Some(tree)) = (frame.shading_of(s.object), &trees[s.object as usize])
            else {
                return out;
            };
            let own = balls
                .objects
                .get(s.object as usize)
                .and_then(Option::as_ref);
            let tb = tree_balls[s.object as usize].as_ref();
            let order = &tree.tree.order;
            let leaves: Vec<(u32, u32)> = tree
                .tree
                .nodes
                .iter()
                .filter(|n| n.is_leaf() && n.end > n.start)
                .map(|n| (n.start, n.end))
                .collect();
            let values: Vec<Rgb> = leaves
                .par_iter()
                .map(|&(start, _)| {
                    let i = order[start as usize] as usize;
                    let ball = tb.map(|b| {
                        let r = own.and_then(|o| o.samples.get(i)).copied();
                        (b, r.unwrap_or(f64::NAN))
                    });
                    single(tree, s.samples[i].position, BOUNCE_EPS, sh, &counts, ball)
                })
                .collect();
            for (&(start, end), v) in leaves.iter().zip(values) {
                for &i in &order[start as usize..end as usize] {
                    if let Some(o) = out.get_mut(i as usize) {
                        *o = v;
                    }
                }
            }
            out
        })
        .collect()
}

/// The radiance arriving at `p` (unit normal `n`) along `dir` from the surfaces (see the
/// module documentation).
#[allow(clippy::too_many_arguments)]
fn radiance_along(
    frame: &Frame<'_>,
    emitters: &Emitters,
    exitance: &[Vec<Rgb>],
    nearest: &[Option<Nearest>],
    by_object: &[Option<usize>],
    p: DVec3,
    n: DVec3,
    dir: DVec3,
    unsampled: &AtomicU64,
) -> Rgb {
    let geom = &frame.geom;
    let origin = geom.offset(p, n, dir);
    let Some(hit) = geom.closest_hit(origin, dir, 0.0, f64::INFINITY) else {
        return [0.0; 3];
    };
    // Only the outside of a surface sends light back out.
    if !(dir.dot(hit.ng) < 0.0) {
        return [0.0; 3];
    }
    let scene = frame.scene;
    let material = &scene.materials[scene.objects[hit.object as usize].material];
    match &material.kind {
        // Opaque surfaces send back nothing here (see the module documentation).
        MaterialKind::Diffuse { .. } => [0.0; 3],
        MaterialKind::Translucent(_) => {
            let Some(sh) = frame.shading_of(hit.object) else {
                unsampled.fetch_add(1, Ordering::Relaxed);
                return [0.0; 3];
            };
            let wo = -dir;
            // The lights in the mirror direction, reflected by the smooth boundary.
            let n_y = if hit.n.dot(wo) > 0.0 { hit.n } else { hit.ng };
            let mirror = (dir - n_y * (2.0 * dir.dot(n_y))).normalize_or_zero();
            let fr = fr_dielectric(n_y.dot(wo).abs(), sh.eta);
            let from = geom.offset(hit.p, hit.ng, mirror);
            let blocked = geom.closest_hit(from, mirror, 0.0, f64::INFINITY);
            let mut lights =
                emitters.quads_hit(from, mirror, blocked.map_or(f64::INFINITY, |h| h.t));
            if blocked.is_none() {
                let env = emitters.escaped(mirror);
                for c in 0..3 {
                    lights[c] += env[c];
                }
            }
            let mut l: Rgb = lights.map(|v| v * fr);
            // The light the medium sends back, from the nearest sample's exitance.
            let j = nearest[hit.object as usize]
                .as_ref()
                .and_then(|near| near.find(hit.p));
            match (j, by_object[hit.object as usize]) {
                (Some(j), Some(k)) => {
                    let m = exitance[k][j];
                    let w = sh.exit_weights(hit.n, wo);
                    for c in 0..3 {
                        l[c] += w[c] * m[c];
                    }
                }
                _ => {
                    unsampled.fetch_add(1, Ordering::Relaxed);
                }
            }
            l
        }
    }
}

/// A unit direction cosine-distributed about the unit vector `n` (Malley's method).
fn cosine_about(n: DVec3, u1: f64, u2: f64) -> DVec3 {
    let (a, b) = n.any_orthonormal_pair();
    let (s, phi) = (u1.sqrt(), 2.0 * PI * u2);
    (a * (s * phi.cos()) + b * (s * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt()).normalize_or(n)
}

/// The grid cell of side `cell` holding `p`, if `p` is finite.
fn cell_of(p: DVec3, cell: f64) -> Option<[i64; 3]> {
    let q = (p / cell).floor();
    q.is_finite()
        .then_some([q.x as i64, q.y as i64, q.z as i64])
}

/// The samples of one object in a grid of cells twice their spacing, for the nearest sample
/// to a surface point.
struct Nearest<'a> {
    samples: &'a ObjectSamples,
    cell: f64,
    grid: HashMap<[i64; 3], Vec<u32>>,
}

impl<'a> Nearest<'a> {
    fn new(samples: &'a ObjectSamples) -> Self {
        let cell = 2.0 * samples.spacing.max(f64::MIN_POSITIVE);
        let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for (i, s) in samples.samples.iter().enumerate() {
            if let Some(c) = cell_of(s.position, cell) {
                grid.entry(c).or_default().push(i as u32);
            }
        }
        Nearest {
            samples,
            cell,
            grid,
        }
    }

    /// The sample nearest `p` within one cell (twice the spacing), if any.
    fn find(&self, p: DVec3) -> Option<usize> {
        let c = cell_of(p, self.cell)?;
        let mut best: Option<(f64, usize)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(list) = self.grid.get(&[c[0] + dx, c[1] + dy, c[2] + dz]) else {
                        continue;
                    };
                    for &i in list {
                        let d2 = (self.samples.samples[i as usize].position - p).length_squared();
                        if best.is_none_or(|(b, _)| d2 < b) {
                            best = Some((d2, i as usize));
                        }
                    }
                }
            }
        }
        best.filter(|(d2, _)| *d2 <= self.cell * self.cell)
            .map(|(_, i)| i)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::irradiance::IrradianceSettings;
    use sss_bssrdf::fresnel::ft_dielectric;
    use sss_scene::load_str;

    /// A 200 × 200 × 20 mm box of skin1 (η 1.4) under a uniform environment of radiance 1, seen
    /// from above.
    fn slab() -> sss_scene::Scene {
        let text = "[camera]\nposition = [0.0, 0.0, 300.0]\ntarget = [0.0, 0.0, 0.0]\n\
                    fov = 10.0\nresolution = [8, 8]\n\n\
                    [[lights]]\ntype = \"environment\"\nradiance = 1.0\n\n\
                    [materials.m]\ntype = \"translucent\"\nmodel = \"mc-table\"\n\
                    preset = \"skin1\"\nunits_per_mm = 1.0\n\n\
                    [[objects]]\nmaterial = \"m\"\nshape = \"box\"\n\
                    size = [200.0, 200.0, 20.0]\ntransform = { translate = [0.0, 0.0, -10.0] }\n";
        load_str(text, "slab.toml", None, &Default::default()).unwrap()
    }

    /// A ray coming down onto the slab at θ brings back the environment reflected by its
    /// smooth surface, F_r(η, cos θ) (Fresnel's equations), plus the exitance of the sample
    /// nearest the hit (found here by brute force; each sample has its own) times the exit
    /// weight W_o = F_t(η, cos θ)/(cπ) (Fresnel's weights); a ray that goes up meets nothing
    /// and brings back nothing.
    #[test]
    fn a_ray_brings_back_the_mirrored_environment_and_the_weighted_exitance() {
        let scene = slab();
        let frame = Frame::prepare(&scene, 1);
        let settings = IrradianceSettings {
            spacing_mfp: 8.0,
            max_samples: 20_000,
            ..IrradianceSettings::default()
        };
        let samples = frame.irradiance_samples(&settings);
        let emitters = Emitters::new(&scene.lights);
        // Each sample its own exitance, so that reading another sample's shows.
        let m_of = |q: DVec3| [0.5 + 0.01 * q.x.abs(), 1.0 + 0.01 * q.y.abs(), 2.0];
        let exitance: Vec<Vec<Rgb>> = samples
            .iter()
            .map(|s| s.samples.iter().map(|q| m_of(q.position)).collect())
            .collect();
        let nearest: Vec<Option<Nearest>> = vec![Some(Nearest::new(&samples[0]))];
        let by_object = vec![Some(0)];
        let sh = frame.shading_of(0).unwrap();
        let unsampled = AtomicU64::new(0);
        let p = DVec3::new(0.0, 0.0, 5.0);
        let along = |dir: DVec3| {
            radiance_along(
                &frame,
                &emitters,
                &exitance,
                &nearest,
                &by_object,
                p,
                DVec3::Z,
                dir,
                &unsampled,
            )
        };
        for theta in [0.0f64, 30.0, 60.0, 80.0] {
            let t = theta.to_radians();
            let dir = DVec3::new(t.sin(), 0.0, -t.cos());
            let l = along(dir);
            let c = t.cos();
            let w = ft_dielectric(c, sh.eta) * sh.norm;
            // The hit on the top face (z = 0) and the sample nearest it, by brute force.
            let hit = p + dir * (p.z / -dir.z);
            let m = samples[0]
                .samples
                .iter()
                .map(|q| q.position)
                .min_by(|a, b| (*a - hit).length().total_cmp(&(*b - hit).length()))
                .map(m_of)
                .unwrap();
            for ch in 0..3 {
                let want = fr_dielectric(c, sh.eta) + w * m[ch];
                assert!(
                    (l[ch] - want).abs() < 1e-9 * want,
                    "θ {theta}: channel {ch} {} against {want}",
                    l[ch]
                );
            }
        }
        assert_eq!(unsampled.load(Ordering::Relaxed), 0);
        let up = along(DVec3::Z);
        assert_eq!(up, [0.0; 3]);
    }

    /// Malley's directions: unit, on the normal's side, with E[cos θ] = 2/3 and E[cos² θ] = 1/2
    /// (the cosine-weighted hemisphere), on a grid of u.
    #[test]
    fn cosine_directions_have_the_cosine_weighted_moments() {
        let n = DVec3::new(0.3, -0.5, 0.8).normalize();
        let k = 200;
        let (mut m1, mut m2) = (0.0, 0.0);
        for i in 0..k {
            for j in 0..k {
                let u1 = (i as f64 + 0.5) / k as f64;
                let u2 = (j as f64 + 0.5) / k as f64;
                let d = cosine_about(n, u1, u2);
                assert!((d.length() - 1.0).abs() < 1e-12);
                let c = d.dot(n);
                assert!(c >= 0.0);
                m1 += c;
                m2 += c * c;
            }
        }
        let count = (k * k) as f64;
        assert!((m1 / count - 2.0 / 3.0).abs() < 1e-4, "{}", m1 / count);
        assert!((m2 / count - 0.5).abs() < 1e-4, "{}", m2 / count);
    }
}
