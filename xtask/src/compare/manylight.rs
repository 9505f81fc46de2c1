//! `cargo xtask compare --manylight`: the claims of Nabata & Iwasaki 2021 (issue 10) measured on
//! our machine, on scenes after the paper's built from the shared meshes (each skipped with a
//! message when its mesh is absent): a Buddha in skin, two Buddhas in skim milk and marble, and
//! a head, each under a quad light of [`VPLS`] VPLs with 16 shading points per pixel
//! (4 with `--quick`).
//!
//! 1. **Estimation accuracy** (Table 1, Fig. 10): the fraction of pixels whose relative error
//!    (of the luminance) is below ε, at ε ∈ {10, 5, 2, 1, 0.5} % and α = 95 %, over a seeded
//!    uniform subset of translucent pixels and several seeds.
//! 2. **BSSRDF-aware against Max-Extent selection** (Table 3): triplets and time at ε = 2 %.
//! 3. **VPL count** (Fig. 9): time and triplets at ×½ … ×8 the VPLs, and **mesh refinement**:
//!    the same at 4× and 16× the triangles (midpoint subdivision).
//! 4. **Pictures** (Fig. 7): the Buddha, and its triplets per pixel with each selection.
//!
//! **The reference.** The paper renders its reference with the method at ε = 0.1 %; on 2 cores
//! that is out of reach (≈ 400× the triplets of ε = 2 %). Instead each subset pixel is
//! estimated with ε = 0 at a fixed triplet count J_ref ([`Plan::ref_triplets`]): the partition
//! is a function of the bounds alone, so at a fixed J the estimate is **unbiased** (the
//! stopping rule is the only source of bias, and there is none here), with a known standard
//! error, stated in the report. That the estimator converges to the brute-force integral is
//! tested in `crates/render/tests/manylight.rs` (`agrees_with_brute_force_within_its_intervals`)
//! and `crates/manylight/tests/estimator.rs`. The reference's own noise widens the measured
//! relative errors: the report gives its median relative standard error next to each ε.
//!
//! **One integral.** The camera samples (hence the shading points) and the VPLs are drawn from
//! the run's seed for the reference and for every run alike; runs differ only in the
//! estimator's random stream (`ManyLight::stream`, the `seed` column of the CSV). Without
//! that, two renders estimate different pixel values (a pixel's 16 jittered camera samples and
//! the jittered VPL grid move with the seed), and the measured "accuracy" falls to 50–70 %
//! whatever the estimator does.
//!
//! Writes `manylight.csv`, `manylight_accuracy.png`, `manylight_vpls.png` and
//! `manylight/*.png` under the output directory.

use super::output::{csv_num, md_num, md_table, write_atomic};
use super::{Context, Error, Experiment, Section};
use sss_bssrdf::Rgb;
use sss_manylight::Selection;
use sss_plot::{Series, SeriesStyle, line_plot, write_error_map};
use sss_render::frame::Frame;
use sss_render::integrators::exact::translucent_pixels;
use sss_render::integrators::manylight::{ManyLight, PixelResult};
use sss_render::metrics::subset_pixels;
use sss_render::progress::NoProgress;
use sss_render::render::{RenderSettings, render};
use sss_render::scene::{self, LoadOptions, Scene, SceneErrorKind};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::time::Instant;

/// VPLs of the quad light (the paper's scenes have 10⁴–10⁵ VPLs of indirect light; ours carry
/// direct light only, so one area light's worth).
pub const VPLS: u32 = 1024;

/// Luminance weights (Rec. 709), as `sss_manylight::LUMINANCE`.
const LUM: [f64; 3] = sss_manylight::LUMINANCE;

fn lum(c: Rgb) -> f64 {
    LUM[0] * c[0] + LUM[1] * c[1] + LUM[2] * c[2]
}

/// The Happy Buddha (2 units high, as the file) in skin1 at 100 mm tall, on a grey ground,
/// under a quad light above and to its left.
pub const BUDDHA: &str = r#"# Buddha in skin, `cargo xtask compare --manylight`.
[camera]
position = [0.0, 0.2, 6.0]
target = [0.0, 0.0, 0.0]
fov = 24.0
resolution = [72, 96]
pixel_samples = 16

[[lights]]
type = "quad"
corner = [-2.5, 2.5, 1.5]
edge_u = [1.5, 0.0, 0.0]
edge_v = [0.0, 0.0, 1.5]
radiance = 30.0

[materials.skin]
type = "translucent"
model = "better-dipole"
preset = "skin1"
units_per_mm = 0.02

[materials.ground]
type = "diffuse"
albedo = 0.5

[[objects]]
name = "ground"
material = "ground"
shape = "plane"
size = [8.0, 8.0]
transform = { translate = [0.0, -1.0, 0.0] }

[[objects]]
name = "buddha"
material = "skin"
shape = "mesh"
file = "happy-buddha-100k.obj"
"#;

/// Two Buddhas side by side, skim milk and marble, lit from the front right.
pub const TWO_BUDDHAS: &str = r#"# Two Buddhas, `cargo xtask compare --manylight`.
[camera]
position = [0.0, 0.2, 7.0]
target = [0.0, 0.0, 0.0]
fov = 24.0
resolution = [112, 84]
pixel_samples = 16

[[lights]]
type = "quad"
corner = [1.5, 2.5, 1.5]
edge_u = [1.5, 0.0, 0.0]
edge_v = [0.0, 0.0, 1.5]
radiance = 30.0

[materials.milk]
type = "translucent"
model = "better-dipole"
preset = "skimmilk"
units_per_mm = 0.02

[materials.marble]
type = "translucent"
model = "better-dipole"
preset = "marble"
units_per_mm = 0.02

[materials.ground]
type = "diffuse"
albedo = 0.5

[[objects]]
name = "ground"
material = "ground"
shape = "plane"
size = [10.0, 8.0]
transform = { translate = [0.0, -1.0, 0.0] }

[[objects]]
name = "milk"
material = "milk"
shape = "mesh"
file = "happy-buddha-100k.obj"
transform = { translate = [-0.55, 0.0, 0.0] }

[[objects]]
name = "marble"
material = "marble"
shape = "mesh"
file = "happy-buddha-100k.obj"
transform = { translate = [0.55, 0.0, 0.0] }
"#;

/// The Lee Perry-Smith head scan (0.45 units wide in the file, about metres) ×10, in skin1 at
/// 0.01 units per mm (true size), lit from the front left by a quad facing it (−z).
pub const HEAD: &str = r#"# Head, `cargo xtask compare --manylight`.
[camera]
position = [0.0, -0.4, 7.0]
target = [0.0, -0.4, 0.0]
fov = 30.0
resolution = [96, 96]
pixel_samples = 16

[[lights]]
type = "quad"
corner = [-3.0, 1.5, 2.5]
edge_u = [0.0, 1.5, 0.0]
edge_v = [1.5, 0.0, 0.0]
radiance = 30.0

[materials.skin]
type = "translucent"
model = "better-dipole"
preset = "skin1"
units_per_mm = 0.01

[[objects]]
name = "head"
material = "skin"
shape = "mesh"
file = "lpshead.obj"
transform = { scale = [10.0, 10.0, 10.0] }
"#;

/// What one configuration runs.
#[derive(Clone, Debug)]
struct Plan {
    /// (name, scene text) of the scenes.
    scenes: Vec<(&'static str, &'static str)>,
    /// Divide the scenes' resolution by this.
    shrink: u32,
    /// Pixel samples per pixel.
    pixel_samples: u32,
    /// Subset pixels per scene.
    subset: usize,
    /// Triplets of each reference estimate (ε = 0).
    ref_triplets: usize,
    /// ε values of the accuracy sweep, loosest first.
    eps: Vec<f64>,
    /// Seeds per ε of the accuracy sweep.
    seeds: u64,
    /// ε of the selection, VPL and mesh experiments.
    fixed_eps: f64,
    /// ε of the full-image pictures (Max-Extent at 2 % over a whole image takes minutes).
    picture_eps: f64,
    /// VPL multipliers of the VPL experiment.
    vpl_factors: Vec<f64>,
    /// Subdivision levels of the mesh experiment (each ×4 triangles).
    subdivisions: Vec<u32>,
}

fn plan(quick: bool) -> Plan {
    if quick {
        Plan {
            scenes: vec![("buddha", BUDDHA)],
            shrink: 2,
            pixel_samples: 4,
            subset: 32,
            ref_triplets: 20_000,
            eps: vec![0.1, 0.05],
            seeds: 1,
            fixed_eps: 0.05,
            picture_eps: 0.05,
            vpl_factors: vec![0.5, 1.0, 2.0],
            subdivisions: vec![0, 1],
        }
    } else {
        Plan {
            scenes: vec![
                ("buddha", BUDDHA),
                ("two-buddhas", TWO_BUDDHAS),
                ("head", HEAD),
            ],
            shrink: 1,
            pixel_samples: 16,
            subset: 64,
            ref_triplets: 300_000,
            eps: vec![0.1, 0.05, 0.02, 0.01, 0.005],
            seeds: 3,
            fixed_eps: 0.02,
            picture_eps: 0.05,
            vpl_factors: vec![0.5, 1.0, 2.0, 4.0, 8.0],
            subdivisions: vec![0, 1, 2],
        }
    }
}

/// One row of `manylight.csv`: a method's estimates of one scene's subset.
#[derive(Clone, Debug)]
struct Row {
    scene: &'static str,
    experiment: &'static str,
    selection: &'static str,
    eps: f64,
    vpls: u32,
    triangles: usize,
    seed: u64,
    seconds: f64,
    pixels: usize,
    mean_triplets: f64,
    /// Fraction of subset pixels with |Î − I| < ε I (luminance).
    accuracy: f64,
    /// RMSE over the subset (pixels and channels).
    rmse: f64,
    /// Pixels that stopped at a cap.
    capped: u64,
}

/// A scene's subset and its reference.
struct Reference {
    pixels: Vec<usize>,
    values: Vec<Rgb>,
    /// Relative standard error of each reference value's luminance.
    rel_se: Vec<f64>,
    seconds: f64,
}

fn selection_name(s: Selection) -> &'static str {
    match s {
        Selection::BssrdfAware => "bssrdf",
        Selection::MaxExtent => "max-extent",
    }
}

/// Loads a scene, scaled to the plan; `None` (with a log line) when its mesh is absent.
fn load(ctx: &Context<'_>, name: &str, text: &str, p: &Plan) -> Result<Option<Scene>, Error> {
    let opts = LoadOptions {
        mesh_dirs: ctx.config.mesh_dirs.clone(),
    };
    match scene::load_str(text, &format!("{name}.toml"), None, &opts) {
        Ok(mut s) => {
            s.camera.width = (s.camera.width / p.shrink).max(8);
            s.camera.height = (s.camera.height / p.shrink).max(8);
            s.camera.pixel_samples = p.pixel_samples;
            Ok(Some(s))
        }
        Err(e) if e.kind == SceneErrorKind::MeshNotFound => {
            (ctx.log)(&format!("manylight: scene {name} skipped ({e})"));
            Ok(None)
        }
        Err(e) => Err(Error(e.to_string())),
    }
}

/// Every translucent mesh of `scene` subdivided `levels` times (each triangle into four at its
/// edge midpoints, shared midpoints welded, normals averaged): the same surface with 4^levels
/// times the triangles.
fn subdivide(scene: &Scene, levels: u32) -> Scene {
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

fn triangles(scene: &Scene) -> usize {
    (0..scene.objects.len())
        .filter(|&o| scene.translucent(o).is_some())
        .map(|o| scene.objects[o].mesh.triangles.len())
        .sum()
}

/// The method with `vpls` VPLs drawn from one fixed seed (the run's), so that the reference
/// and every run estimate the same integral whatever their own seeds.
fn base(ctx: &Context<'_>, vpls: u32) -> ManyLight {
    ManyLight {
        vpls,
        vpl_seed: Some(ctx.config.seed),
        ..ManyLight::default()
    }
}

/// Runs `m` on the subset `pixels` of `scene` with estimator stream `stream`, timed (frame
/// set-up included). The G-buffer is always the run's seed's: every run estimates the same
/// pixel values (the camera samples depend on the frame's seed).
fn shade(
    ctx: &Context<'_>,
    scene: &Scene,
    m: &ManyLight,
    pixels: &[usize],
    stream: u64,
) -> Result<(Vec<PixelResult>, f64), Error> {
    let t0 = Instant::now();
    let frame = Frame::prepare(scene, ctx.config.seed);
    let m = ManyLight { stream, ..*m };
    let out = m
        .shade_pixels(&frame, pixels)
        .map_err(|e| Error(format!("scene {}: manylight: {e}", scene.name)))?;
    Ok((out, t0.elapsed().as_secs_f64()))
}

fn reference(ctx: &Context<'_>, scene: &Scene, p: &Plan) -> Result<Reference, Error> {
    let seed = ctx.config.seed;
    let frame = Frame::prepare(scene, seed);
    let all = translucent_pixels(&frame);
    let pixels = subset_pixels(&all, p.subset, seed ^ 0x4d4c);
    drop(frame);
    let m = ManyLight {
        eps: 0.0,
        max_triplets: p.ref_triplets,
        max_splits: p.ref_triplets,
        ..base(ctx, VPLS)
    };
    (ctx.log)(&format!(
        "manylight: {} reference, {} pixels at {} triplets",
        scene.name,
        pixels.len(),
        p.ref_triplets
    ));
    // A seed of its own: the reference's samples are independent of every run it scores.
    let (out, seconds) = shade(ctx, scene, &m, &pixels, 0x5245_4600)?;
    let values: Vec<Rgb> = out.iter().map(|r| r.subsurface).collect();
    let rel_se = out
        .iter()
        .map(|r| {
            let v = lum(r.subsurface);
            if v > 0.0 { lum(r.std_error) / v } else { 0.0 }
        })
        .collect();
    Ok(Reference {
        pixels,
        values,
        rel_se,
        seconds,
    })
}

/// Accuracy (|Î − I| < ε I on the luminance, over pixels whose reference is > 0) and RMSE.
fn score(out: &[PixelResult], r: &Reference, eps: f64) -> (f64, f64, usize) {
    let (mut n, mut ok, mut se) = (0usize, 0usize, 0.0);
    for (o, v) in out.iter().zip(&r.values) {
        for (x, y) in o.subsurface.iter().zip(v) {
            se += (x - y) * (x - y);
        }
        let (a, b) = (lum(o.subsurface), lum(*v));
        if b > 0.0 {
            n += 1;
            if (a - b).abs() < eps * b {
                ok += 1;
            }
        }
    }
    let rmse = (se / (3 * out.len().max(1)) as f64).sqrt();
    (if n > 0 { ok as f64 / n as f64 } else { 0.0 }, rmse, n)
}

/// The manylight experiment.
pub struct ManyLightExperiment;

impl Experiment for ManyLightExperiment {
    fn name(&self) -> &'static str {
        "manylight"
    }

    fn run(&self, ctx: &Context<'_>) -> Result<Section, Error> {
        let cfg = ctx.config;
        let p = plan(cfg.quick);
        let mut rows: Vec<Row> = Vec::new();
        let mut refs: Vec<(&'static str, Reference, usize)> = Vec::new();
        let mut skipped: Vec<String> = Vec::new();
        let dir = cfg.out.join("manylight");
        std::fs::create_dir_all(&dir)
            .map_err(|e| Error(format!("cannot create {}: {e}", dir.display())))?;
        for &(name, text) in &p.scenes {
            let Some(scene) = load(ctx, name, text, &p)? else {
                skipped.push(name.into());
                continue;
            };
            let r = reference(ctx, &scene, &p)?;
            let tri = triangles(&scene);
            let run = |m: &ManyLight,
                       sc: &Scene,
                       experiment: &'static str,
                       seed: u64,
                       rows: &mut Vec<Row>|
             -> Result<(), Error> {
                (ctx.log)(&format!(
                    "manylight: {name} {experiment} ε={} {} VPLs {} seed {seed}",
                    m.eps,
                    m.vpls,
                    selection_name(m.selection)
                ));
                let (out, seconds) = shade(ctx, sc, m, &r.pixels, seed)?;
                let (accuracy, rmse, pixels) = score(&out, &r, m.eps);
                let n = out.len().max(1) as f64;
                rows.push(Row {
                    scene: name,
                    experiment,
                    selection: selection_name(m.selection),
                    eps: m.eps,
                    vpls: m.vpls,
                    triangles: triangles(sc),
                    seed,
                    seconds,
                    pixels,
                    mean_triplets: out.iter().map(|o| o.triplets).sum::<f64>() / n,
                    accuracy,
                    rmse,
                    capped: out
                        .iter()
                        .map(|o| o.summary.triplet_cap + o.summary.split_cap)
                        .sum(),
                });
                Ok(())
            };
            let ours = |eps: f64| ManyLight {
                eps,
                ..base(ctx, VPLS)
            };
            // 1. Accuracy against ε.
            for &eps in &p.eps {
                for k in 0..p.seeds {
                    run(&ours(eps), &scene, "accuracy", cfg.seed + 1 + k, &mut rows)?;
                }
            }
            // 2. Max-Extent at the fixed ε (BSSRDF-aware's rows are the sweep's at that ε).
            let max_extent = ManyLight {
                selection: Selection::MaxExtent,
                ..ours(p.fixed_eps)
            };
            run(&max_extent, &scene, "selection", cfg.seed + 1, &mut rows)?;
            if !p.eps.contains(&p.fixed_eps) {
                run(
                    &ours(p.fixed_eps),
                    &scene,
                    "selection",
                    cfg.seed + 1,
                    &mut rows,
                )?;
            }
            // 3. VPLs and mesh refinement, on the first scene only.
            if refs.is_empty() {
                for &f in &p.vpl_factors {
                    let m = ManyLight {
                        eps: p.fixed_eps,
                        ..base(ctx, ((VPLS as f64 * f).round() as u32).max(1))
                    };
                    run(&m, &scene, "vpls", cfg.seed + 1, &mut rows)?;
                }
                for &l in &p.subdivisions {
                    let fine = subdivide(&scene, l);
                    run(&ours(p.fixed_eps), &fine, "mesh", cfg.seed + 1, &mut rows)?;
                }
                pictures(ctx, &scene, &p, &dir)?;
            }
            refs.push((name, r, tri));
        }
        write_atomic(&cfg.out.join("manylight.csv"), csv(&rows).as_bytes())?;
        plots(ctx, &rows, &p)?;
        Ok(report(&rows, &refs, &skipped, &p))
    }
}

/// Full renders of the first scene at the picture ε with both selections: the image and the
/// triplets per pixel (Fig. 7).
fn pictures(
    ctx: &Context<'_>,
    scene: &Scene,
    p: &Plan,
    dir: &std::path::Path,
) -> Result<(), Error> {
    let e = |e: sss_render::Error| Error(e.to_string());
    let settings = RenderSettings {
        seed: ctx.config.seed,
        ..RenderSettings::default()
    };
    let (w, h) = (scene.camera.width, scene.camera.height);
    let mut layers = Vec::new();
    for sel in [Selection::BssrdfAware, Selection::MaxExtent] {
        let m = ManyLight {
            eps: p.picture_eps,
            selection: sel,
            ..base(ctx, VPLS)
        };
        (ctx.log)(&format!(
            "manylight: {} picture, {} at ε={}",
            scene.name,
            selection_name(sel),
            p.picture_eps
        ));
        let out = render(scene, &m, &settings, &NoProgress).map_err(e)?;
        if sel == Selection::BssrdfAware {
            let path = dir.join(format!("{}.png", scene.name));
            let exposure = sss_render::image::auto_exposure(&out.total);
            sss_render::image::write_png(&path, w, h, &out.total, exposure).map_err(e)?;
        }
        let t = out
            .layers
            .iter()
            .find(|l| l.name == "triplets")
            .map(|l| l.pixels.iter().map(|v| v[0]).collect::<Vec<f64>>())
            .unwrap_or_default();
        let covered: Vec<bool> = out.coverage.iter().map(|&c| c > 0.0).collect();
        layers.push((sel, t, covered));
    }
    // One colour scale for both: the larger 99th percentile.
    let mut all: Vec<f64> = layers
        .iter()
        .flat_map(|(_, t, c)| t.iter().zip(c).filter(|(_, c)| **c).map(|(v, _)| *v))
        .collect();
    all.sort_by(f64::total_cmp);
    let max = all
        .get(((all.len() as f64) * 0.99) as usize)
        .copied()
        .unwrap_or(1.0)
        .max(1.0);
    for (sel, t, covered) in &layers {
        let values: Vec<Option<f64>> = t
            .iter()
            .zip(covered)
            .map(|(v, c)| if *c && *v > 0.0 { Some(*v) } else { None })
            .collect();
        let path = dir.join(format!(
            "{}_triplets_{}.png",
            scene.name,
            selection_name(*sel)
        ));
        write_error_map(
            &path,
            w,
            h,
            &values,
            max,
            &format!(
                "{}: triplets per pixel, {}",
                scene.name,
                selection_name(*sel)
            ),
            "triplets",
        )
        .map_err(|e| Error(format!("{}: {e}", path.display())))?;
    }
    Ok(())
}

fn csv(rows: &[Row]) -> String {
    let mut s = String::from(
        "scene,experiment,selection,eps,vpls,triangles,seed,seconds,pixels,mean_triplets,\
         accuracy,rmse,capped\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.scene,
            r.experiment,
            r.selection,
            r.eps,
            r.vpls,
            r.triangles,
            r.seed,
            csv_num(Some(r.seconds)),
            r.pixels,
            csv_num(Some(r.mean_triplets)),
            csv_num(Some(r.accuracy)),
            csv_num(Some(r.rmse)),
            r.capped
        );
    }
    s
}

/// Mean accuracy over seeds and its binomial standard error over all pixel estimates.
fn pooled(rows: &[&Row]) -> (f64, f64, usize) {
    let n: usize = rows.iter().map(|r| r.pixels).sum();
    if n == 0 {
        return (0.0, 0.0, 0);
    }
    let ok: f64 = rows.iter().map(|r| r.accuracy * r.pixels as f64).sum();
    let a = ok / n as f64;
    (a, (a * (1.0 - a) / n as f64).sqrt(), n)
}

fn plots(ctx: &Context<'_>, rows: &[Row], p: &Plan) -> Result<(), Error> {
    let out = &ctx.config.out;
    let scenes: Vec<&str> = p.scenes.iter().map(|s| s.0).collect();
    let mut acc = Vec::new();
    for name in &scenes {
        let pts: Vec<(f64, f64)> = p
            .eps
            .iter()
            .filter_map(|&eps| {
                let rs: Vec<&Row> = rows
                    .iter()
                    .filter(|r| r.scene == *name && r.experiment == "accuracy" && r.eps == eps)
                    .collect();
                (!rs.is_empty()).then(|| (100.0 * eps, 100.0 * pooled(&rs).0))
            })
            .collect();
        if !pts.is_empty() {
            acc.push(Series {
                name: (*name).into(),
                points: pts,
                color: None,
                style: SeriesStyle::LineMarkers,
                ..Series::default()
            });
        }
    }
    if !acc.is_empty() {
        acc.push(Series {
            name: "α = 95 %".into(),
            points: vec![
                (100.0 * p.eps[p.eps.len() - 1], 95.0),
                (100.0 * p.eps[0], 95.0),
            ],
            color: Some([120, 120, 120]),
            style: SeriesStyle::Dashed,
            ..Series::default()
        });
        line_plot(
            &out.join("manylight_accuracy.png"),
            "Estimation accuracy against ε (fraction with relative error < ε)",
            "ε (%)",
            "accuracy (%)",
            &acc,
            true,
            false,
        )
        .map_err(|e| Error(format!("manylight_accuracy.png: {e}")))?;
    }
    let vp: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.experiment == "vpls")
        .map(|r| (r.vpls as f64, r.seconds))
        .collect();
    if !vp.is_empty() {
        line_plot(
            &out.join("manylight_vpls.png"),
            "Subset time against VPL count",
            "VPLs",
            "seconds",
            &[Series {
                name: "manylight".into(),
                points: vp,
                color: None,
                style: SeriesStyle::LineMarkers,
                ..Series::default()
            }],
            true,
            true,
        )
        .map_err(|e| Error(format!("manylight_vpls.png: {e}")))?;
    }
    Ok(())
}

fn report(
    rows: &[Row],
    refs: &[(&'static str, Reference, usize)],
    skipped: &[String],
    p: &Plan,
) -> Section {
    let title = "Many-light SSS (Nabata & Iwasaki 2021) at paper scale".to_string();
    let mut summary = String::new();
    let mut body = String::new();
    if refs.is_empty() {
        let _ = writeln!(
            summary,
            "Skipped: no scene's mesh was found ({}); set SSS_MESH_DIR to the shared meshes.",
            skipped.join(", ")
        );
        return Section {
            title,
            summary,
            body,
        };
    }
    let _ = writeln!(
        body,
        "Scenes at {} pixel samples per pixel, {} VPLs (one quad light, direct light only); each \
         scored on a seeded subset of {} translucent pixels against an unbiased reference: the \
         method at ε = 0 with exactly {} triplets per pixel estimate.\n",
        p.pixel_samples, VPLS, p.subset, p.ref_triplets
    );
    let mut ref_rows = Vec::new();
    for (name, r, tri) in refs {
        let mut se = r.rel_se.clone();
        se.sort_by(f64::total_cmp);
        let med = se.get(se.len() / 2).copied().unwrap_or(0.0);
        ref_rows.push(vec![
            (*name).to_string(),
            tri.to_string(),
            r.pixels.len().to_string(),
            md_num(Some(r.seconds), 3),
            format!("{} %", md_num(Some(100.0 * med), 2)),
        ]);
    }
    body.push_str("**References**\n\n");
    body.push_str(&md_table(
        &[
            "scene",
            "triangles",
            "pixels",
            "seconds",
            "median relative SE",
        ],
        &ref_rows,
    ));
    // 1. Accuracy.
    let mut acc_rows = Vec::new();
    for (name, r, _) in refs {
        let mut se = r.rel_se.clone();
        se.sort_by(f64::total_cmp);
        let med = se.get(se.len() / 2).copied().unwrap_or(0.0);
        for &eps in &p.eps {
            let rs: Vec<&Row> = rows
                .iter()
                .filter(|x| x.scene == *name && x.experiment == "accuracy" && x.eps == eps)
                .collect();
            if rs.is_empty() {
                continue;
            }
            let (a, a_se, n) = pooled(&rs);
            let secs = rs.iter().map(|x| x.seconds).sum::<f64>() / rs.len() as f64;
            let trip = rs.iter().map(|x| x.mean_triplets).sum::<f64>() / rs.len() as f64;
            let rmse = rs.iter().map(|x| x.rmse).sum::<f64>() / rs.len() as f64;
            let capped: u64 = rs.iter().map(|x| x.capped).sum();
            acc_rows.push(vec![
                (*name).to_string(),
                format!("{} %", 100.0 * eps),
                format!(
                    "{} ± {} %",
                    md_num(Some(100.0 * a), 3),
                    md_num(Some(100.0 * a_se), 2)
                ),
                n.to_string(),
                md_num(Some(trip), 3),
                md_num(Some(secs), 3),
                md_num(Some(rmse), 3),
                capped.to_string(),
                format!("{} %", md_num(Some(100.0 * med / eps), 2)),
            ]);
        }
    }
    body.push_str("\n**Estimation accuracy** (Table 1, Fig. 10: the fraction of pixel estimates whose relative error is below ε, α = 95 %; ± the binomial standard error)\n\n");
    body.push_str(&md_table(
        &[
            "scene",
            "ε",
            "accuracy",
            "estimates",
            "mean triplets",
            "seconds (subset)",
            "RMSE",
            "capped",
            "ref. SE / ε",
        ],
        &acc_rows,
    ));
    body.push_str(
        "\nThe last column is the reference's median relative standard error over ε: where it is \
         not small, the reference's own noise lowers the measured accuracy.\n",
    );
    // 2. Selection.
    let mut sel_rows = Vec::new();
    for (name, _, _) in refs {
        let find = |sel: &str| {
            rows.iter().find(|x| {
                x.scene == *name
                    && x.eps == p.fixed_eps
                    && x.selection == sel
                    && x.seed == rows.iter().map(|y| y.seed).min().unwrap_or(0)
                    && (x.experiment == "accuracy" || x.experiment == "selection")
            })
        };
        if let (Some(b), Some(m)) = (find("bssrdf"), find("max-extent")) {
            sel_rows.push(vec![
                (*name).to_string(),
                md_num(Some(b.mean_triplets), 3),
                md_num(Some(m.mean_triplets), 3),
                md_num(Some(m.mean_triplets / b.mean_triplets.max(1e-300)), 3),
                md_num(Some(b.seconds), 3),
                md_num(Some(m.seconds), 3),
            ]);
        }
    }
    let _ = writeln!(
        body,
        "\n**BSSRDF-aware against Max-Extent** (Table 3) at ε = {} %\n",
        100.0 * p.fixed_eps
    );
    body.push_str(&md_table(
        &[
            "scene",
            "triplets, BSSRDF-aware",
            "triplets, Max-Extent",
            "ratio",
            "seconds, BSSRDF-aware",
            "seconds, Max-Extent",
        ],
        &sel_rows,
    ));
    // 3. VPLs and mesh.
    let vrows: Vec<Vec<String>> = rows
        .iter()
        .filter(|x| x.experiment == "vpls" || x.experiment == "mesh")
        .map(|x| {
            vec![
                x.scene.to_string(),
                x.experiment.to_string(),
                x.vpls.to_string(),
                x.triangles.to_string(),
                md_num(Some(x.mean_triplets), 3),
                md_num(Some(x.seconds), 3),
            ]
        })
        .collect();
    let _ = writeln!(
        body,
        "\n**VPL count and mesh refinement** (Fig. 9) at ε = {} %\n",
        100.0 * p.fixed_eps
    );
    body.push_str(&md_table(
        &[
            "scene",
            "experiment",
            "VPLs",
            "triangles",
            "mean triplets",
            "seconds (subset)",
        ],
        &vrows,
    ));
    if let Some((name, _, _)) = refs.first() {
        let _ = writeln!(
            body,
            "\nThe pictures are at ε = {} %.\n",
            100.0 * p.picture_eps
        );
        let _ = writeln!(
            body,
            "\n![{name}](manylight/{name}.png) ![triplets, BSSRDF-aware](manylight/{name}_triplets_bssrdf.png) ![triplets, Max-Extent](manylight/{name}_triplets_max-extent.png)\n\n![accuracy](manylight_accuracy.png) ![VPLs](manylight_vpls.png)"
        );
    }
    if !skipped.is_empty() {
        let _ = writeln!(body, "\nSkipped (mesh absent): {}.", skipped.join(", "));
    }
    // Summary: accuracy per ε pooled over scenes.
    let mut parts = Vec::new();
    for &eps in &p.eps {
        let rs: Vec<&Row> = rows
            .iter()
            .filter(|x| x.experiment == "accuracy" && x.eps == eps)
            .collect();
        if !rs.is_empty() {
            let (a, a_se, _) = pooled(&rs);
            parts.push(format!(
                "{} % at ε = {} % (± {})",
                md_num(Some(100.0 * a), 3),
                100.0 * eps,
                md_num(Some(100.0 * a_se), 2)
            ));
        }
    }
    let _ = writeln!(
        summary,
        "Estimation accuracy over {} scene(s) (the paper: 94.8–94.9 % at α = 95 %): {}.",
        refs.len(),
        parts.join("; ")
    );
    Section {
        title,
        summary,
        body,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sss_render::scene::builtin;

    /// Area of every translucent triangle of a scene.
    fn area(s: &Scene) -> f64 {
        let mut a = 0.0;
        for o in 0..s.objects.len() {
            if s.translucent(o).is_none() {
                continue;
            }
            let m = &s.objects[o].mesh;
            for t in &m.triangles {
                let [p, q, r] = t.map(|k| m.positions[k as usize]);
                a += 0.5 * (q - p).cross(r - p).length();
            }
        }
        a
    }

    #[test]
    fn subdivision_keeps_the_surface_and_welds_midpoints() {
        let s = builtin("sphere", &LoadOptions::default()).unwrap();
        let (t0, a0) = (triangles(&s), area(&s));
        let o = (0..s.objects.len())
            .find(|&o| s.translucent(o).is_some())
            .unwrap();
        let v0 = s.objects[o].mesh.positions.len();
        let f = subdivide(&s, 2);
        assert_eq!(triangles(&f), 16 * t0);
        // Midpoints lie on the flat triangles: the area is unchanged to rounding.
        assert!((area(&f) - a0).abs() < 1e-9 * a0, "{} vs {a0}", area(&f));
        // A closed mesh: V − E + F = 2 before and after, so with E = 3F/2 each level adds
        // exactly E vertices (one per welded edge): V' = V + 3F/2.
        let m = &f.objects[o].mesh;
        let v1 = v0 + 3 * t0 / 2;
        let v2 = v1 + 3 * (4 * t0) / 2;
        assert_eq!(m.positions.len(), v2);
        assert_eq!(m.normals.len(), m.positions.len());
        assert!(m.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-9));
        // Opaque objects are left alone.
        for k in 0..s.objects.len() {
            if s.translucent(k).is_none() {
                assert_eq!(
                    s.objects[k].mesh.triangles.len(),
                    f.objects[k].mesh.triangles.len()
                );
            }
        }
    }

    #[test]
    fn accuracy_counts_relative_errors_below_eps() {
        let r = Reference {
            pixels: vec![0, 1, 2, 3],
            values: vec![[1.0; 3], [1.0; 3], [2.0; 3], [0.0; 3]],
            rel_se: vec![0.0; 4],
            seconds: 0.0,
        };
        let px = |v: f64| PixelResult {
            subsurface: [v; 3],
            ..PixelResult::default()
        };
        // 1.04 (4 %), 0.9 (10 %), 2.06 (3 %); the black reference pixel is not counted.
        let out = [px(1.04), px(0.9), px(2.06), px(0.5)];
        let (a, rmse, n) = score(&out, &r, 0.05);
        assert_eq!(n, 3);
        assert!((a - 2.0 / 3.0).abs() < 1e-12);
        let want = ((0.04f64.powi(2) + 0.1f64.powi(2) + 0.06f64.powi(2) + 0.25) / 4.0).sqrt();
        assert!((rmse - want).abs() < 1e-12, "{rmse} vs {want}");
        // Pooled over two runs of different sizes: weighted by estimates.
        let row = |accuracy: f64, pixels: usize| Row {
            scene: "s",
            experiment: "accuracy",
            selection: "bssrdf",
            eps: 0.05,
            vpls: 1,
            triangles: 1,
            seed: 1,
            seconds: 0.0,
            pixels,
            mean_triplets: 0.0,
            accuracy,
            rmse: 0.0,
            capped: 0,
        };
        let (r1, r2) = (row(1.0, 30), row(0.5, 10));
        let (a, se, n) = pooled(&[&r1, &r2]);
        assert_eq!(n, 40);
        assert!((a - 35.0 / 40.0).abs() < 1e-12);
        assert!((se - (a * (1.0 - a) / 40.0).sqrt()).abs() < 1e-12);
    }
}
