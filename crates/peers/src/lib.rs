//! # sss-peers: the same scene in another renderer
//!
//! Runs a scene of the toolkit in the renderers users would otherwise reach for, so that
//! images can be compared like for like: Mitsuba 3 (its Python package, the `scalar_rgb`
//! variant and `volpathmis`, a smooth `dielectric` around a `homogeneous` medium) and Blender
//! Cycles (the `bpy` package: the medium inside glass, or its random-walk and
//! Christensen–Burley subsurface at Cycles' own parameters, [`CyclesMode`]). Use it to
//! check a renderer against code we did not write, or to put a peer on the same
//! error-against-time axes as our methods.
//!
//! [`export`] writes a [`Scene`] as `scene.json` plus one OBJ per object (positions, vertex
//! normals and triangles exactly as the renderer sees them, so both renderers trace the same
//! triangles with the same shading normals); the peer's script (embedded here, written next to
//! the scene: `scripts/`) builds the peer's scene from it and writes independent images
//! (batches, so each pixel's noise can be estimated), which [`read_render`] reads back. [`find_python`] finds an interpreter that can import the peer's
//! package: `SSS_PEERS_PYTHON` if set, else `python3`; when there is none it says how to
//! install it, so that callers can skip with that sentence.
//!
//! Conventions (`docs/peers.md` has how each was matched and checked): lengths in scene units,
//! coefficients per scene unit (the material's 1/mm divided by its `units_per_mm`); a pinhole
//! camera with a vertical field of view and box-filtered pixels; quad lights one-sided,
//! environment lights constant; the peer's image holds the light reflected by the dielectric
//! boundaries too, so [`mitsuba_subsurface`] subtracts a render whose media are opaque black
//! (the light that never crossed a boundary) to keep the subsurface term that `sss` renders.
//!
//! ```no_run
//! use sss_peers::{MitsubaRun, RR_DEFAULT, export, find_python, mitsuba_subsurface};
//! use sss_scene::{LoadOptions, builtin};
//!
//! let scene = builtin("backlit", &LoadOptions::default())?;
//! let python = find_python(&["mitsuba", "numpy"]).map_err(|why| format!("skipped: {why}"))?;
//! let dir = std::env::temp_dir().join("backlit-mitsuba");
//! let json = export(&scene, &dir)?;
//! let run = MitsubaRun { spp: 64, batches: 4, seed: 0, threads: 2, rr_depth: RR_DEFAULT };
//! let render = mitsuba_subsurface(&python, &json, &run)?;
//! let (mean, variance) = (render.mean(), render.variance_of_mean());
//! assert_eq!(mean.len(), (render.width * render.height) as usize);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! ## Papers
//! None: the peers' physics is pbrt 3rd ed. §15.3 (volumetric path tracing) as Mitsuba 3
//! implements it.

#![forbid(unsafe_code)]

use glam::DVec3;
use serde_json::{Value, json};
use sss_scene::{Light, MaterialKind, Mesh, Scene};
use sss_util::{Rgb, write_atomic};
use std::fmt;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The Mitsuba 3 script (`scripts/mitsuba_render.py`).
pub const MITSUBA_SCRIPT: &str = include_str!("../scripts/mitsuba_render.py");

/// The Blender Cycles script (`scripts/cycles_render.py`).
pub const CYCLES_SCRIPT: &str = include_str!("../scripts/cycles_render.py");

/// The environment variable naming the Python interpreter that has the peers' packages.
pub const PYTHON_VAR: &str = "SSS_PEERS_PYTHON";

/// A failure, with a message for a person.
#[derive(Debug)]
pub struct Error(pub String);

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Error {}

fn io_error(what: &str, path: &Path, e: std::io::Error) -> Error {
    Error(format!("{what} {}: {e}", path.display()))
}

/// The Python interpreter that can import `modules` (e.g. `["mitsuba", "numpy"]`):
/// `$SSS_PEERS_PYTHON` if set, else `python3`. Otherwise one sentence saying what failed and
/// how to install the packages.
pub fn find_python(modules: &[&str]) -> Result<PathBuf, String> {
    let module = modules.join(" ");
    let (python, from_var) = match std::env::var_os(PYTHON_VAR) {
        Some(p) if !p.is_empty() => (PathBuf::from(p), true),
        _ => (PathBuf::from("python3"), false),
    };
    let how = format!(
        "install it with `python3 -m venv peers && peers/bin/pip install {module}` and set \
         {PYTHON_VAR}=peers/bin/python"
    );
    let out = Command::new(&python)
        .args(["-c", &format!("import {}", modules.join(", "))])
        .output();
    match out {
        Ok(o) if o.status.success() => Ok(python),
        Ok(o) => {
            let err = String::from_utf8_lossy(&o.stderr);
            let last = err.lines().last().unwrap_or("").trim().to_string();
            Err(format!(
                "{} cannot import {module} ({last}){}; {how}",
                python.display(),
                if from_var {
                    format!(" (from {PYTHON_VAR})")
                } else {
                    String::new()
                }
            ))
        }
        Err(e) => Err(format!("cannot run {}: {e}; {how}", python.display())),
    }
}

/// A mesh as OBJ text: `v`, `vn` (one normal per position) and `f a//a b//b c//c`, numbers in
/// Rust's shortest round-trip form, so the peer reads the same f64 values (as its own floats).
pub fn mesh_obj(mesh: &Mesh) -> String {
    use std::fmt::Write as _;
    let mut s = String::with_capacity(64 * (mesh.positions.len() + mesh.triangles.len()));
    for p in &mesh.positions {
        let _ = writeln!(s, "v {} {} {}", p.x, p.y, p.z);
    }
    for n in &mesh.normals {
        let _ = writeln!(s, "vn {} {} {}", n.x, n.y, n.z);
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        let _ = writeln!(s, "f {a}//{a} {b}//{b} {c}//{c}");
    }
    s
}

fn vec3(v: DVec3) -> Value {
    json!([v.x, v.y, v.z])
}

/// The scene as the peers' scripts read it (see `scripts/`): camera, lights, and per object
/// its mesh file (`object_<i>.obj`) and material, coefficients per scene unit.
pub fn scene_json(scene: &Scene) -> Value {
    let c = &scene.camera;
    let lights: Vec<Value> = scene
        .lights
        .iter()
        .map(|l| match l {
            Light::Quad {
                corner,
                edge_u,
                edge_v,
                radiance,
            } => json!({"type": "quad", "corner": vec3(*corner), "edge_u": vec3(*edge_u),
                         "edge_v": vec3(*edge_v), "radiance": radiance}),
            Light::Environment { radiance } => {
                json!({"type": "environment", "radiance": radiance})
            }
            Light::Point {
                position,
                intensity,
            } => json!({"type": "point", "position": vec3(*position), "intensity": intensity}),
            Light::Directional {
                direction,
                irradiance,
            } => json!({"type": "directional", "direction": vec3(*direction),
                         "irradiance": irradiance}),
            Light::Sun {
                direction,
                irradiance,
                half_angle,
            } => json!({"type": "sun", "direction": vec3(*direction), "irradiance": irradiance,
                         "angular_diameter": 2.0 * half_angle}),
        })
        .collect();
    let objects: Vec<Value> = scene
        .objects
        .iter()
        .enumerate()
        .map(|(i, o)| {
            let material = match &scene.materials[o.material].kind {
                MaterialKind::Translucent(t) => {
                    let m = &t.medium;
                    let u = t.units_per_mm;
                    let per_unit = |v: Rgb| v.map(|x| x / u);
                    json!({"type": "medium", "sigma_a": per_unit(m.sigma_a()),
                           "sigma_s": per_unit(m.sigma_s()), "g": m.g(), "eta": m.eta()})
                }
                MaterialKind::Diffuse { albedo, .. } => {
                    json!({"type": "diffuse", "albedo": albedo})
                }
            };
            json!({"name": o.name, "mesh": format!("object_{i}.obj"), "material": material})
        })
        .collect();
    json!({
        "camera": {"position": vec3(c.position), "target": vec3(c.target), "up": vec3(c.up),
                   "vfov_deg": c.vfov_deg, "width": c.width, "height": c.height},
        "lights": lights,
        "objects": objects,
    })
}

/// Writes `scene` into `dir` (created if needed) as `scene.json`, `object_<i>.obj` per object
/// and the peers' scripts; returns the path of `scene.json`.
pub fn export(scene: &Scene, dir: &Path) -> Result<PathBuf, Error> {
    std::fs::create_dir_all(dir).map_err(|e| io_error("cannot create", dir, e))?;
    for (i, o) in scene.objects.iter().enumerate() {
        let p = dir.join(format!("object_{i}.obj"));
        write_atomic(&p, mesh_obj(&o.mesh).as_bytes())
            .map_err(|e| io_error("cannot write", &p, e))?;
    }
    for (name, text) in [
        ("mitsuba_render.py", MITSUBA_SCRIPT),
        ("cycles_render.py", CYCLES_SCRIPT),
    ] {
        let script = dir.join(name);
        write_atomic(&script, text.as_bytes()).map_err(|e| io_error("cannot write", &script, e))?;
    }
    let p = dir.join("scene.json");
    let text = serde_json::to_string_pretty(&scene_json(scene))
        .map_err(|e| Error(format!("cannot format {}: {e}", p.display())))?;
    write_atomic(&p, text.as_bytes()).map_err(|e| io_error("cannot write", &p, e))?;
    Ok(p)
}

/// A peer's renders of one scene: independent images (batches) of the same settings, linear
/// RGB, rows from the top, box-filtered pixels.
#[derive(Clone, Debug, PartialEq)]
pub struct PeerRender {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Each batch's pixels, row-major from the top-left.
    pub batches: Vec<Vec<Rgb>>,
    /// The peer's own render time in seconds over all batches (scene loading excluded).
    pub seconds: f64,
}

impl PeerRender {
    /// The mean image over the batches.
    pub fn mean(&self) -> Vec<Rgb> {
        let k = self.batches.len().max(1) as f64;
        let n = self.width as usize * self.height as usize;
        let mut out = vec![[0.0; 3]; n];
        for b in &self.batches {
            for (o, p) in out.iter_mut().zip(b) {
                for c in 0..3 {
                    o[c] += p[c] / k;
                }
            }
        }
        out
    }

    /// Per pixel, the variance of [`Self::mean`] estimated from the spread of the batches
    /// (the unbiased sample variance over K batches, divided by K; 0 for one batch).
    pub fn variance_of_mean(&self) -> Vec<Rgb> {
        let k = self.batches.len();
        let mean = self.mean();
        if k < 2 {
            return vec![[0.0; 3]; mean.len()];
        }
        let kf = k as f64;
        let mut out = vec![[0.0; 3]; mean.len()];
        for b in &self.batches {
            for ((o, p), m) in out.iter_mut().zip(b).zip(&mean) {
                for c in 0..3 {
                    let d = p[c] - m[c];
                    o[c] += d * d / ((kf - 1.0) * kf);
                }
            }
        }
        out
    }
}

/// Reads `<prefix>.f32` (batches × height × width × 3 little-endian f32) and `<prefix>.json`
/// (seconds, width, height, batches), as the peers' scripts write them.
pub fn read_render(prefix: &Path) -> Result<PeerRender, Error> {
    let meta_path = prefix.with_extension("json");
    let meta_text =
        std::fs::read_to_string(&meta_path).map_err(|e| io_error("cannot read", &meta_path, e))?;
    let meta: Value = serde_json::from_str(&meta_text)
        .map_err(|e| Error(format!("{}: not JSON: {e}", meta_path.display())))?;
    let field = |k: &str| {
        meta.get(k)
            .and_then(Value::as_f64)
            .ok_or_else(|| Error(format!("{}: no number `{k}`", meta_path.display())))
    };
    let (w, h, k, seconds) = (
        field("width")?,
        field("height")?,
        field("batches")?,
        field("seconds")?,
    );
    let whole = |x: f64| x >= 1.0 && x.fract() == 0.0 && x <= 1e9;
    if !(whole(w) && whole(h) && whole(k) && w * h * k <= 1e9) {
        return Err(Error(format!(
            "{}: bad size {w} × {h} × {k} batches",
            meta_path.display()
        )));
    }
    let (w, h, k) = (w as u32, h as u32, k as usize);
    let data_path = prefix.with_extension("f32");
    let bytes = std::fs::read(&data_path).map_err(|e| io_error("cannot read", &data_path, e))?;
    let n = w as usize * h as usize;
    if bytes.len() != k * n * 12 {
        return Err(Error(format!(
            "{}: {} bytes, expected {} for {k} × {w} × {h} RGB f32",
            data_path.display(),
            bytes.len(),
            k * n * 12
        )));
    }
    let f = |i: usize| f32::from_le_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    let mut batches = Vec::with_capacity(k);
    for b in 0..k {
        let mut pixels = Vec::with_capacity(n);
        for p in 0..n {
            let at = 12 * (b * n + p);
            let px = [0, 1, 2].map(|c| f64::from(f(at + 4 * c)));
            if px.iter().any(|v| !v.is_finite()) {
                return Err(Error(format!(
                    "{}: batch {b} pixel {p} is not finite: {px:?}",
                    data_path.display()
                )));
            }
            pixels.push(px);
        }
        batches.push(pixels);
    }
    Ok(PeerRender {
        width: w,
        height: h,
        batches,
        seconds,
    })
}

/// One Mitsuba 3 run's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MitsubaRun {
    /// Samples per pixel of each batch.
    pub spp: u32,
    /// Independent images, seeded `seed`, `seed + 1`, ...
    pub batches: u32,
    /// Mitsuba's sampler seed of the first batch.
    pub seed: u64,
    /// Threads (0: Mitsuba's default, all cores).
    pub threads: usize,
    /// The path depth where Mitsuba's Russian roulette starts (its default: 5). Its roulette
    /// survives with probability min(max throughput · η², 0.95), so a walk of n collisions
    /// carries a weight up to 0.95^(5 − n): in media of albedo near 1 (marble, milk), whose
    /// walks run to hundreds of collisions, the estimate is heavy-tailed and its mean converges
    /// slowly from below. [`RR_NEVER`] turns the roulette off.
    pub rr_depth: u32,
}

/// A Russian-roulette depth no path reaches ([`MitsubaRun::rr_depth`]).
pub const RR_NEVER: u32 = 1_000_000_000;

/// Mitsuba's default Russian-roulette depth.
pub const RR_DEFAULT: u32 = 5;

/// Runs the Mitsuba script on `scene_json` (from [`export`]) in `mode` (`full`: the whole
/// image; `subsurface`: minus the light the dielectric boundaries reflect, see
/// [`mitsuba_subsurface`]), writing `<scene dir>/<name>.f32|json`; returns the batches.
pub fn render_mitsuba(
    python: &Path,
    scene_json: &Path,
    run: &MitsubaRun,
    mode: &str,
    name: &str,
) -> Result<PeerRender, Error> {
    let args = [
        ("--spp", run.spp.to_string()),
        ("--batches", run.batches.max(1).to_string()),
        ("--seed", run.seed.to_string()),
        ("--threads", run.threads.to_string()),
        ("--mode", mode.to_string()),
        ("--rr-depth", run.rr_depth.to_string()),
    ];
    run_script(python, "mitsuba_render.py", scene_json, name, &args)
}

/// Blender Cycles' ways to render a medium: the medium itself inside glass, or its subsurface
/// closures at Cycles' own parameters (inverted from the medium by `cycles_render.py`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CyclesMode {
    /// A smooth Glass BSDF around Volume Absorption + Volume Scatter: the same physics as
    /// Mitsuba's and `volpath`'s.
    Volume,
    /// The Principled BSDF's "Random Walk" subsurface.
    RandomWalk,
    /// The Principled BSDF's "Random Walk (Skin)" subsurface.
    RandomWalkSkin,
    /// The Principled BSDF's "Christensen-Burley" subsurface.
    Burley,
}

impl CyclesMode {
    /// Every mode, in report order.
    pub const ALL: [CyclesMode; 4] = [
        CyclesMode::Volume,
        CyclesMode::RandomWalk,
        CyclesMode::RandomWalkSkin,
        CyclesMode::Burley,
    ];

    /// The script's name for it.
    pub fn name(self) -> &'static str {
        match self {
            CyclesMode::Volume => "volume",
            CyclesMode::RandomWalk => "random-walk",
            CyclesMode::RandomWalkSkin => "random-walk-skin",
            CyclesMode::Burley => "burley",
        }
    }
}

/// One Cycles run's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CyclesRun {
    /// Samples per pixel of each batch.
    pub spp: u32,
    /// Independent images, seeded `seed`, `seed + 1`, ...
    pub batches: u32,
    /// Cycles' seed of the first batch.
    pub seed: u64,
    /// Threads (0: Blender's default, all cores).
    pub threads: usize,
    /// How the medium is rendered.
    pub mode: CyclesMode,
}

/// Runs the Cycles script on `scene_json` (from [`export`]), writing `<scene dir>/<name>.f32|json`;
/// returns the batches. Cycles hides the lights from glossy rays instead of subtracting a
/// render, so its image is the subsurface term directly.
pub fn render_cycles(
    python: &Path,
    scene_json: &Path,
    run: &CyclesRun,
    name: &str,
) -> Result<PeerRender, Error> {
    let args = [
        ("--spp", run.spp.to_string()),
        ("--batches", run.batches.max(1).to_string()),
        ("--seed", run.seed.to_string()),
        ("--threads", run.threads.to_string()),
        ("--mode", run.mode.name().to_string()),
    ];
    run_script(python, "cycles_render.py", scene_json, name, &args)
}

/// Runs `script` (written next to `scene_json` by [`export`]) with `args`, and reads what it
/// wrote to `<scene dir>/<name>`.
fn run_script(
    python: &Path,
    script: &str,
    scene_json: &Path,
    name: &str,
    args: &[(&str, String)],
) -> Result<PeerRender, Error> {
    let dir = scene_json.parent().unwrap_or(Path::new("."));
    let prefix = dir.join(name);
    let mut cmd = Command::new(python);
    cmd.arg(dir.join(script)).arg(scene_json).arg(&prefix);
    for (k, v) in args {
        cmd.arg(k).arg(v);
    }
    let out = cmd
        .output()
        .map_err(|e| Error(format!("cannot run {}: {e}", python.display())))?;
    if !out.status.success() {
        let err = String::from_utf8_lossy(&out.stderr);
        let tail: Vec<&str> = err.lines().rev().take(3).collect();
        return Err(Error(format!(
            "{script} on {} failed ({}): {}",
            scene_json.display(),
            out.status,
            tail.into_iter().rev().collect::<Vec<_>>().join(" | ")
        )));
    }
    read_render(&prefix)
}

/// Mitsuba's subsurface term of the scene, per batch: a full render minus a render with the
/// same seed whose media are opaque black (the light the boundaries reflect without it ever
/// entering); its time is the full renders'. The difference is not clamped (a noisy pixel may
/// dip below 0), so that means and noise estimates stay unbiased.
pub fn mitsuba_subsurface(
    python: &Path,
    scene_json: &Path,
    run: &MitsubaRun,
) -> Result<PeerRender, Error> {
    render_mitsuba(
        python,
        scene_json,
        run,
        "subsurface",
        &format!("subsurface_{}_{}", run.seed, run.spp),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use sss_scene::{LoadOptions, builtin};

    #[test]
    fn the_exported_scene_names_every_object_and_light() {
        let scene = builtin("picnic", &LoadOptions::default()).unwrap();
        let v = scene_json(&scene);
        assert_eq!(v["objects"].as_array().unwrap().len(), scene.objects.len());
        assert_eq!(v["lights"].as_array().unwrap().len(), scene.lights.len());
        // The ketchup sphere: sigma per scene unit = per mm / units_per_mm (0.01).
        let k = v["objects"]
            .as_array()
            .unwrap()
            .iter()
            .find(|o| o["material"]["type"] == "medium")
            .unwrap();
        assert!(k["material"]["eta"].as_f64().unwrap() > 1.0);
    }

    #[test]
    fn obj_text_round_trips_positions_and_normals() {
        let scene = builtin("sphere", &LoadOptions::default()).unwrap();
        let mesh = &scene.objects[0].mesh;
        let text = mesh_obj(mesh);
        let mut v = Vec::new();
        let mut f = 0;
        for line in text.lines() {
            let w: Vec<&str> = line.split(' ').collect();
            match w[0] {
                "v" => v.push([1, 2, 3].map(|i| w[i].parse::<f64>().unwrap())),
                "f" => f += 1,
                _ => {}
            }
        }
        assert_eq!(f, mesh.triangles.len());
        for (a, b) in v.iter().zip(&mesh.positions) {
            assert_eq!(*a, [b.x, b.y, b.z]);
        }
    }

    #[test]
    fn renders_read_back_with_their_batch_statistics_and_bad_ones_fail() {
        let dir = std::env::temp_dir().join(format!("sss-peers-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let prefix = dir.join("img");
        std::fs::write(
            prefix.with_extension("json"),
            r#"{"seconds": 1.5, "width": 2, "height": 1, "batches": 2}"#,
        )
        .unwrap();
        std::fs::write(prefix.with_extension("f32"), [0u8; 44]).unwrap();
        let e = read_render(&prefix).unwrap_err().to_string();
        assert!(e.contains("img.f32") && e.contains("expected 48"), "{e}");
        let mut bytes = Vec::new();
        for v in [
            1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0, 3.0, 2.0, 1.0, 4.0, 5.0, 8.0,
        ] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        std::fs::write(prefix.with_extension("f32"), &bytes).unwrap();
        let r = read_render(&prefix).unwrap();
        assert_eq!(r.batches[1], vec![[3.0, 2.0, 1.0], [4.0, 5.0, 8.0]]);
        assert_eq!((r.width, r.height, r.seconds), (2, 1, 1.5));
        assert_eq!(r.mean(), vec![[2.0, 2.0, 2.0], [4.0, 5.0, 7.0]]);
        // Two batches a, b: the variance of their mean is (a − b)²/4.
        assert_eq!(r.variance_of_mean(), vec![[1.0, 0.0, 1.0], [0.0, 0.0, 1.0]]);
        bytes[0..4].copy_from_slice(&f32::NAN.to_le_bytes());
        std::fs::write(prefix.with_extension("f32"), &bytes).unwrap();
        let e = read_render(&prefix).unwrap_err().to_string();
        assert!(e.contains("batch 0 pixel 0 is not finite"), "{e}");
        std::fs::write(
            prefix.with_extension("json"),
            r#"{"seconds": 1.5, "width": 0, "height": 1, "batches": 2}"#,
        )
        .unwrap();
        let e = read_render(&prefix).unwrap_err().to_string();
        assert!(e.contains("bad size"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Cycles' albedo fit and its inversion (in the script, run by Python with numpy): at
    /// g = 0 the base colour 0.620 gives skin1's red single-scattering albedo 0.9585
    /// (`../shared/docs/peers-howto.md`: skin1 inverted to 0.620 / 0.381 / 0.239), and the
    /// bisection inverts the fit to 10⁻⁹ for g in [0, 0.9] (Cycles' range). Skips without numpy.
    #[test]
    fn the_cycles_script_inverts_its_albedo_fit() {
        let Ok(python) = find_python(&["numpy"]) else {
            eprintln!("skipped: no Python with numpy");
            return;
        };
        let dir = std::env::temp_dir().join(format!("sss-peers-cycles-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let script = dir.join("cycles_render.py");
        std::fs::write(&script, CYCLES_SCRIPT).unwrap();
        let code = format!(
            "import importlib.util as u\n\
             s = u.spec_from_file_location('c', {:?}); m = u.module_from_spec(s); \
             s.loader.exec_module(m)\n\
             print(m.cycles_alpha(0.620, 0.0))\n\
             for (a, g) in [(0.3, 0.0), (0.9585, 0.0), (0.99, 0.5), (0.7, 0.3), (0.5, 0.9)]:\n    \
                 A = m.invert_alpha(a, g); print(abs(m.cycles_alpha(A, g) - a))\n",
            script.display().to_string()
        );
        let out = Command::new(&python).args(["-c", &code]).output().unwrap();
        std::fs::remove_dir_all(&dir).ok();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8_lossy(&out.stdout).to_string();
        let v: Vec<f64> = text.lines().map(|l| l.trim().parse().unwrap()).collect();
        assert!((v[0] - 0.9585).abs() < 5e-4, "{}", v[0]);
        assert!(v[1..].iter().all(|e| *e < 1e-9), "{v:?}");
    }
}
