//! The seed corpora: built-in scenes, tiny OBJ meshes (and the head of a shared mesh when
//! `../shared/meshes` exists), G-buffer EXRs written by `sss_render::image::write_exr`, and
//! `sss` argument lists over every subcommand.

use sss_bssrdf::Rgb;
use std::path::{Path, PathBuf};

/// Tiny valid OBJ meshes: a tetrahedron, a quad with normals and texture coordinates, a cube
/// of quads with negative (relative) indices, and a triangle with groups and materials.
pub const TINY_OBJS: &[(&str, &str)] = &[
    (
        "tetra.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    ),
    (
        "quad.obj",
        "# a unit quad\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
         vn 0 1 0\nf 1/1/1 4/4/1 3/3/1 2/2/1\n",
    ),
    (
        "cube.obj",
        "o cube\nv -0.5 -0.5 -0.5\nv 0.5 -0.5 -0.5\nv 0.5 0.5 -0.5\nv -0.5 0.5 -0.5\n\
         v -0.5 -0.5 0.5\nv 0.5 -0.5 0.5\nv 0.5 0.5 0.5\nv -0.5 0.5 0.5\n\
         f -8 -5 -6 -7\nf -4 -3 -2 -1\nf -8 -7 -3 -4\nf -6 -5 -1 -2\nf -8 -4 -1 -5\nf -7 -6 -2 -3\n",
    ),
    (
        "tri.obj",
        "mtllib none.mtl\ng one\nusemtl skin\ns 1\nv 0.0 0.0 0.0\nv 1.0e0 0.0 0.0\nv 0.0 1.0 0.0\n\
         vn 0 0 1\nvn 0 0 1\nvn 0 0 1\nf 1//1 2//2 3//3\n",
    ),
];

/// The scene header (camera, one light, one translucent material `m`) of the small scenes.
const HEAD: &str = "[camera]\nposition = [0.0, 0.5, 4.0]\ntarget = [0.0, 0.0, 0.0]\nfov = 35.0\n\
resolution = [16, 12]\n\n[[lights]]\ntype = \"point\"\nposition = [2.0, 3.0, 3.0]\n\
intensity = 50.0\n\n[materials.m]\ntype = \"translucent\"\nmodel = \"better-dipole\"\n\
preset = \"skin1\"\nunits_per_mm = 0.05\n";

/// A small scene whose one object is the mesh `file` (relative to the scene's directory).
pub fn mesh_scene(file: &str) -> String {
    format!(
        "{HEAD}\n[[objects]]\nname = \"mesh\"\nmaterial = \"m\"\nshape = \"mesh\"\nfile = \"{file}\"\n\
         transform = {{ translate = [0.0, -0.2, 0.0], scale = 1.0 }}\n"
    )
}

/// A 16x12 scene with one coarse sphere: cheap enough to render in milliseconds.
pub fn tiny_sphere_scene() -> String {
    format!(
        "{HEAD}\n[[objects]]\nname = \"ball\"\nmaterial = \"m\"\nshape = \"sphere\"\nradius = 1.0\n\
         subdivisions = 2\n"
    )
}

/// Scene texts: the built-in scenes, the tiny sphere and a scene naming each tiny OBJ.
pub fn scenes() -> Vec<Vec<u8>> {
    let mut out: Vec<Vec<u8>> = sss_render::scene::BUILTIN_SCENES
        .iter()
        .map(|(_, text)| text.as_bytes().to_vec())
        .collect();
    out.push(tiny_sphere_scene().into_bytes());
    for (name, _) in TINY_OBJS {
        out.push(mesh_scene(name).into_bytes());
    }
    out
}

/// Largest head of a shared mesh taken into the OBJ corpus.
const SHARED_HEAD_BYTES: usize = 4096;

/// OBJ texts: the tiny meshes, then the first few KB (cut at a line end) of the first two
/// meshes in `shared` when that directory exists (skipped silently otherwise).
pub fn objs(shared: &Path) -> Vec<Vec<u8>> {
    let mut out: Vec<Vec<u8>> = TINY_OBJS
        .iter()
        .map(|(_, t)| t.as_bytes().to_vec())
        .collect();
    let Ok(entries) = std::fs::read_dir(shared) else {
        return out;
    };
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj")))
        .collect();
    files.sort();
    for path in files.iter().take(2) {
        use std::io::Read;
        let mut head = Vec::new();
        let read = std::fs::File::open(path)
            .and_then(|f| f.take(SHARED_HEAD_BYTES as u64).read_to_end(&mut head));
        if read.is_ok()
            && let Some(end) = head.iter().rposition(|&b| b == b'\n')
        {
            head.truncate(end + 1);
            out.push(head);
        }
    }
    out
}

/// Per-pixel G-buffer layers of a `w`x`h` frame: `irradiance`, and `surface` (depth, world
/// size of a pixel, object id + 1, with a border of pixels that see no object).
pub fn gbuffer_layers(w: usize, h: usize) -> (Vec<Rgb>, Vec<Rgb>) {
    let mut irr = Vec::with_capacity(w * h);
    let mut surface = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let inside = x > 0 && y > 0 && x + 1 < w && y + 1 < h;
            let id = if !inside {
                0.0
            } else if x < w / 2 {
                1.0
            } else {
                2.0
            };
            irr.push([0.5 + 0.1 * x as f64, 0.4, 0.3 + 0.05 * y as f64]);
            surface.push([4.0 + 0.01 * (x + y) as f64, 0.01, id]);
        }
    }
    (irr, surface)
}

/// Writes the EXR corpus into `dir` and returns the files' bytes: G-buffers (layers
/// `irradiance` and `surface`, as `sss render --method separable --gbuffer` writes them) of
/// 8x6 and 1x1 pixels, and a render-like file (layers `total` and `subsurface`).
pub fn exrs(dir: &Path) -> Result<Vec<Vec<u8>>, String> {
    let mut out = Vec::new();
    for (name, w, h) in [("gbuffer.exr", 8usize, 6usize), ("gbuffer1.exr", 1, 1)] {
        let (irr, surface) = gbuffer_layers(w, h);
        let path = dir.join(name);
        write_gbuffer(&path, w, h, &irr, &surface)?;
        out.push(std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?);
    }
    let path = dir.join("render.exr");
    let (irr, surface) = gbuffer_layers(4, 3);
    sss_render::image::write_exr(&path, 4, 3, &[("total", &irr), ("subsurface", &surface)])
        .map_err(|e| e.to_string())?;
    out.push(std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?);
    Ok(out)
}

/// Writes a G-buffer EXR (layers `irradiance` and `surface`).
pub fn write_gbuffer(
    path: &Path,
    w: usize,
    h: usize,
    irr: &[Rgb],
    surface: &[Rgb],
) -> Result<(), String> {
    sss_render::image::write_exr(
        path,
        w as u32,
        h as u32,
        &[("irradiance", irr), ("surface", surface)],
    )
    .map_err(|e| e.to_string())
}

/// The files the `cli` target's argument lists name, all in one work directory.
pub struct CliFiles {
    /// The work directory (outputs must stay inside it).
    pub dir: PathBuf,
    /// The tiny scene (`render` runs only on it).
    pub scene: PathBuf,
    /// A G-buffer for `filter`.
    pub gbuffer: PathBuf,
    /// Two renders (layers `total`, `subsurface`) for `diff`.
    pub image_a: PathBuf,
    /// The reference of `diff`.
    pub image_b: PathBuf,
}

impl CliFiles {
    /// Writes the scene and the images into `dir`.
    pub fn write(dir: &Path) -> Result<CliFiles, String> {
        let files = CliFiles {
            dir: dir.to_path_buf(),
            scene: dir.join("tiny.toml"),
            gbuffer: dir.join("gbuffer.exr"),
            image_a: dir.join("a.exr"),
            image_b: dir.join("b.exr"),
        };
        std::fs::write(&files.scene, tiny_sphere_scene())
            .map_err(|e| format!("{}: {e}", files.scene.display()))?;
        let (irr, surface) = gbuffer_layers(16, 12);
        write_gbuffer(&files.gbuffer, 16, 12, &irr, &surface)?;
        for (path, scale) in [(&files.image_a, 1.0), (&files.image_b, 1.1)] {
            let a: Vec<Rgb> = irr.iter().map(|p| p.map(|v| v * scale)).collect();
            sss_render::image::write_exr(path, 16, 12, &[("total", &a), ("subsurface", &a)])
                .map_err(|e| e.to_string())?;
        }
        Ok(files)
    }

    /// The seed argument lists (program name first) over every subcommand.
    pub fn arg_lists(&self) -> Vec<Vec<String>> {
        let d = |name: &str| self.dir.join(name).display().to_string();
        let scene = self.scene.display().to_string();
        let g = self.gbuffer.display().to_string();
        let (a, b) = (
            self.image_a.display().to_string(),
            self.image_b.display().to_string(),
        );
        let lists: Vec<Vec<String>> = vec![
            vec![
                "render".into(),
                scene.clone(),
                "--method".into(),
                "exact".into(),
                "--spacing".into(),
                "1.0".into(),
                "--out".into(),
                d("exact.exr"),
            ],
            vec![
                "render".into(),
                scene.clone(),
                "--method".into(),
                "pathtrace".into(),
                "--spp".into(),
                "2".into(),
                "--seed".into(),
                "3".into(),
                "--png".into(),
                d("pt.png"),
            ],
            vec![
                "render".into(),
                scene,
                "--method".into(),
                "separable".into(),
                "--taps".into(),
                "9".into(),
                "--kernel".into(),
                "svd3".into(),
                "--threads".into(),
                "1".into(),
                "--gbuffer".into(),
                d("g.exr"),
            ],
            vec![
                "diff".into(),
                a.clone(),
                b.clone(),
                "--layer".into(),
                "total".into(),
                "--png".into(),
                d("diff.png"),
            ],
            vec!["diff".into(), a, b, "--eps".into(), "0.01".into()],
            vec![
                "kernel".into(),
                "--preset".into(),
                "skin1".into(),
                "--method".into(),
                "svd3".into(),
                "--format".into(),
                "glsl".into(),
            ],
            vec![
                "kernel".into(),
                "--sigma-a".into(),
                "0.1,0.2,0.3".into(),
                "--sigma-s".into(),
                "1,2,3".into(),
                "--g".into(),
                "0.5".into(),
                "--eta".into(),
                "1.3".into(),
                "--method".into(),
                "artist".into(),
                "--taps".into(),
                "11".into(),
                "--normalize".into(),
            ],
            vec![
                "filter".into(),
                g.clone(),
                "--preset".into(),
                "marble".into(),
                "--units-per-mm".into(),
                "0.05".into(),
                "--out".into(),
                d("f.exr"),
            ],
            vec![
                "filter".into(),
                g,
                "--preset".into(),
                "skin2".into(),
                "--units-per-mm".into(),
                "0.05".into(),
                "--kernel".into(),
                "guided".into(),
                "--k".into(),
                "1.5".into(),
                "--jitter".into(),
                "0.5".into(),
                "--out".into(),
                d("f2.exr"),
                "--png".into(),
                d("f2.png"),
            ],
            vec![
                "profile".into(),
                "--model".into(),
                "better-dipole".into(),
                "--preset".into(),
                "skin1".into(),
                "--r-max".into(),
                "10".into(),
                "--steps".into(),
                "20".into(),
            ],
            vec![
                "profile".into(),
                "--model".into(),
                "pbd".into(),
                "--sigma-a".into(),
                "0.01,0.02,0.03".into(),
                "--sigma-s".into(),
                "2,2,2".into(),
                "--r-max".into(),
                "5".into(),
                "--steps".into(),
                "8".into(),
                "--log".into(),
                "--plot".into(),
                d("p.svg"),
            ],
            vec![
                "profile".into(),
                "--model".into(),
                "monte-carlo".into(),
                "--preset".into(),
                "ketchup".into(),
                "--r-max".into(),
                "5".into(),
                "--steps".into(),
                "10".into(),
                "--photons".into(),
                "2000".into(),
            ],
            vec!["presets".into(), "--csv".into()],
        ];
        lists
            .into_iter()
            .map(|mut l| {
                if l[0] == "render" {
                    // The guard runs renders only under a 64 MiB budget.
                    l.extend(["--max-memory".to_string(), "64M".to_string()]);
                }
                std::iter::once("sss".to_string()).chain(l).collect()
            })
            .collect()
    }

    /// Arguments the mutator inserts: subcommands, every flag, and values for them.
    pub fn pool(&self) -> Vec<String> {
        let fixed = [
            "render",
            "diff",
            "kernel",
            "filter",
            "profile",
            "presets",
            "--method",
            "exact",
            "pathtrace",
            "separable",
            "--spp",
            "--spacing",
            "--max-samples",
            "--taps",
            "--uniform-taps",
            "--kernel",
            "--k",
            "--jitter",
            "preintegrated",
            "svd1",
            "svd6",
            "artist",
            "guided",
            "gaussians1",
            "gaussians6",
            "--artist-preset",
            "close-fit",
            "production",
            "--seed",
            "--threads",
            "--max-memory",
            "64M",
            "1K",
            "--mesh-dir",
            "--out",
            "--png",
            "--gbuffer",
            "--plot",
            "--layer",
            "subsurface",
            "std_error",
            "--eps",
            "--solid-angle",
            "--rel-error",
            "--model",
            "standard-dipole",
            "better-dipole",
            "directional-dipole",
            "pbd",
            "burley",
            "mc-table",
            "monte-carlo",
            "--preset",
            "skin1",
            "marble",
            "apple",
            "--sigma-a",
            "--sigma-s",
            "0,0,0",
            "1e308,1,1",
            "--g",
            "--eta",
            "--units-per-mm",
            "--r-max",
            "--steps",
            "--log",
            "--photons",
            "--format",
            "json",
            "csv",
            "hlsl",
            "wgsl",
            "--normalize",
            "--uniform",
            "--csv",
            "--help",
            "-V",
            "--",
            "-",
        ];
        let mut pool: Vec<String> = fixed.iter().map(|s| s.to_string()).collect();
        for name in [
            "o.exr",
            "o.png",
            "p.svg",
            "p.png",
            "a.exr",
            "b.exr",
            "g.exr",
            "tiny.toml",
        ] {
            pool.push(self.dir.join(name).display().to_string());
        }
        for p in [&self.scene, &self.gbuffer, &self.image_a] {
            pool.push(p.display().to_string());
        }
        pool
    }
}
