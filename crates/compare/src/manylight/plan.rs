//! What the many-light comparison runs: its scenes (`scenes/experiments/manylight-*.toml`),
//! their point-lit and subdivided variants, and the [`Plan`] of a full or `--quick` run.

use super::*;

/// VPLs of the quad light (the paper's scenes have 10⁴–10⁵ VPLs of indirect light; ours carry
/// direct light only, so one area light's worth).
pub const VPLS: u32 = 1024;

/// The Happy Buddha (2 units high, as the file) in skin1 at 100 mm tall, on a grey ground,
/// under a quad light above and to its left.
pub const BUDDHA: &str = include_str!("../../../../scenes/experiments/manylight-buddha.toml");

/// Two Buddhas side by side, skim milk and marble, lit from the front right.
pub const TWO_BUDDHAS: &str =
    include_str!("../../../../scenes/experiments/manylight-two-buddhas.toml");

/// The Lee Perry-Smith head scan (0.45 units wide in the file, about metres) ×10, in skin1 at
/// 0.01 units per mm (true size), lit from the front left by a quad facing it (−z).
pub const HEAD: &str = include_str!("../../../../scenes/experiments/manylight-head.toml");

/// How a scene of the comparison is lit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Lighting {
    /// As its file: one quad light of [`VPLS`] VPLs, [`Plan::pixel_samples`] per pixel.
    Quad,
    /// The quad replaced by one point light at its centre ([`point_lit`]), with
    /// [`POINT_PIXEL_SAMPLES`] camera samples per pixel: one VPL, so the light tree cannot split
    /// and the estimator's whole work is on the triangles.
    Point,
}

/// Camera samples per pixel of the point-lit variants (as a user would first try a scene).
pub(super) const POINT_PIXEL_SAMPLES: u32 = 4;

/// One scene of the comparison.
#[derive(Clone, Copy, Debug)]
pub(super) struct SceneSpec {
    /// Its name in the CSV and the report (`-point` added for [`Lighting::Point`]).
    pub(super) name: &'static str,
    /// The scene file's text.
    pub(super) text: &'static str,
    pub(super) lighting: Lighting,
    /// Whether the baselines run their whole N sweep and EELC its ε sweep here (Table 1,
    /// Fig. 10); elsewhere they run at [`Plan::eelc_points`] and the fixed ε only.
    pub(super) sweep_baselines: bool,
}

/// The Stanford dragon (14 units long in the file) ×0.1 in skin1 with the standard dipole at
/// 0.01 units per mm (a 140 mm dragon: thin claws and horns, deep folds), on a grey ground,
/// under a quad light above and to its right, in front.
pub const DRAGON: &str = include_str!("../../../../scenes/experiments/manylight-dragon.toml");

/// What one configuration runs.
#[derive(Clone, Debug)]
pub(super) struct Plan {
    /// The scenes.
    pub(super) scenes: Vec<SceneSpec>,
    /// Divide the scenes' resolution by this.
    pub(super) shrink: u32,
    /// Pixel samples per pixel of the quad-lit scenes.
    pub(super) pixel_samples: u32,
    /// Subset pixels per scene.
    pub(super) subset: usize,
    /// The path-traced reference's paths.
    pub(super) reference: Budget,
    /// ε values of the accuracy sweep, loosest first.
    pub(super) eps: Vec<f64>,
    /// Seeds per ε of the accuracy sweep.
    pub(super) seeds: u64,
    /// ε of the selection, VPL and mesh experiments.
    pub(super) fixed_eps: f64,
    /// ε of the full-image pictures (Max-Extent at 2 % over a whole image takes minutes).
    pub(super) picture_eps: f64,
    /// VPL multipliers of the VPL experiment.
    pub(super) vpl_factors: Vec<f64>,
    /// Subdivision levels of the mesh experiment (each ×4 triangles).
    pub(super) subdivisions: Vec<u32>,
    /// Irradiance points per shading point of the baselines' importance-sampled sweeps.
    pub(super) points_is: Vec<u32>,
    /// Irradiance points per shading point of the baselines' uniform sweeps.
    pub(super) points_uniform: Vec<u32>,
    /// Irradiance points per shading point of EELC's accuracy sweep (importance-sampled).
    pub(super) eelc_points: u32,
}

/// A scene of the plan.
pub(super) const fn spec(
    name: &'static str,
    text: &'static str,
    lighting: Lighting,
    sweep_baselines: bool,
) -> SceneSpec {
    SceneSpec {
        name,
        text,
        lighting,
        sweep_baselines,
    }
}

pub(super) fn plan(quick: bool) -> Plan {
    use Lighting::{Point, Quad};
    if quick {
        Plan {
            scenes: vec![
                spec("buddha", BUDDHA, Quad, true),
                spec("dragon-point", DRAGON, Point, false),
            ],
            shrink: 2,
            pixel_samples: 4,
            subset: 32,
            reference: Budget {
                pilot: 64,
                target_rel_se: 0.008,
                fine_pixels: 0,
                fine_rel_se: 0.008,
                max_paths: 1 << 20,
            },
            eps: vec![0.1, 0.05],
            seeds: 1,
            fixed_eps: 0.05,
            picture_eps: 0.05,
            vpl_factors: vec![0.5, 1.0, 2.0],
            subdivisions: vec![0, 1],
            points_is: vec![16, 64],
            points_uniform: vec![64],
            eelc_points: 64,
        }
    } else {
        Plan {
            scenes: vec![
                spec("buddha", BUDDHA, Quad, true),
                spec("two-buddhas", TWO_BUDDHAS, Quad, true),
                spec("head", HEAD, Quad, true),
                spec("buddha-point", BUDDHA, Point, false),
                spec("two-buddhas-point", TWO_BUDDHAS, Point, false),
                spec("head-point", HEAD, Point, false),
                spec("dragon-point", DRAGON, Point, false),
            ],
            shrink: 1,
            pixel_samples: 16,
            subset: 40,
            reference: Budget {
                pilot: 256,
                target_rel_se: 0.005,
                fine_pixels: 10,
                fine_rel_se: 0.0023,
                max_paths: 1 << 22,
            },
            eps: vec![0.1, 0.05, 0.02, 0.01],
            seeds: 6,
            fixed_eps: 0.02,
            picture_eps: 0.1,
            vpl_factors: vec![0.5, 1.0, 2.0, 4.0, 8.0],
            subdivisions: vec![0, 1, 2],
            points_is: vec![64, 256, 1024],
            points_uniform: vec![1024],
            eelc_points: 1024,
        }
    }
}

/// Loads a scene, scaled to the plan and lit as `spec` asks; `None` (with a log line) when its
/// mesh is absent.
pub(super) fn load(ctx: &Context<'_>, spec: &SceneSpec, p: &Plan) -> Result<Option<Scene>, Error> {
    let opts = LoadOptions {
        mesh_dirs: ctx.config.mesh_dirs.clone(),
    };
    match scene::load_str(spec.text, &format!("{}.toml", spec.name), None, &opts) {
        Ok(mut s) => {
            s.camera.width = (s.camera.width / p.shrink).max(8);
            s.camera.height = (s.camera.height / p.shrink).max(8);
            s.camera.pixel_samples = p.pixel_samples;
            if spec.lighting == Lighting::Point {
                s = point_lit(&s);
                s.camera.pixel_samples = POINT_PIXEL_SAMPLES;
            }
            s.name = spec.name.to_string();
            Ok(Some(s))
        }
        Err(e) if e.kind == SceneErrorKind::MeshNotFound => {
            (ctx.log)(&format!("manylight: scene {} skipped ({e})", spec.name));
            Ok(None)
        }
        Err(e) => Err(Error(e.to_string())),
    }
}

/// `scene` with each quad light replaced by an isotropic point light at its centre, of
/// intensity L·A (the quad's intensity along its normal: a cosine emitter of radiance L and
/// area A), so that what the quad faced keeps about its brightness.
pub(super) fn point_lit(scene: &Scene) -> Scene {
    let mut s = scene.clone();
    for l in &mut s.lights {
        if let Light::Quad {
            corner,
            edge_u,
            edge_v,
            radiance,
        } = *l
        {
            let area = edge_u.cross(edge_v).length();
            *l = Light::Point {
                position: corner + 0.5 * (edge_u + edge_v),
                intensity: radiance.map(|v| v * area),
            };
        }
    }
    s
}

/// Every translucent mesh of `scene` subdivided `levels` times (each triangle into four at its
/// edge midpoints, shared midpoints welded, normals averaged): the same surface with 4^levels
/// times the triangles.
pub(super) fn subdivide(scene: &Scene, levels: u32) -> Scene {
    let mut s = scene.clone();
    for o in 0..s.objects.len() {
        if s.translucent(o).is_none() {
            continue;
        }
        let mesh = &mut s.objects[o].mesh;
        for _ in 0..levels {
            let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
            let mut tris = Vec::with_capacity(4 * mesh.triangles.len());
            let mut midpoint = |a: u32, b: u32, mesh: &mut sss_render::scene::Mesh| -> u32 {
                let key = (a.min(b), a.max(b));
                *mid.entry(key).or_insert_with(|| {
                    let (pa, pb) = (mesh.positions[a as usize], mesh.positions[b as usize]);
                    let (na, nb) = (mesh.normals[a as usize], mesh.normals[b as usize]);
                    mesh.positions.push(0.5 * (pa + pb));
                    let n = (na + nb).normalize_or_zero();
                    mesh.normals
                        .push(if n.length_squared() > 0.0 { n } else { na });
                    (mesh.positions.len() - 1) as u32
                })
            };
            let old = std::mem::take(&mut mesh.triangles);
            for [a, b, c] in old {
                let ab = midpoint(a, b, mesh);
                let bc = midpoint(b, c, mesh);
                let ca = midpoint(c, a, mesh);
                tris.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
            }
            mesh.triangles = tris;
        }
    }
    s
}

pub(super) fn triangles(scene: &Scene) -> usize {
    (0..scene.objects.len())
        .filter(|&o| scene.translucent(o).is_some())
        .map(|o| scene.objects[o].mesh.triangles.len())
        .sum()
}
