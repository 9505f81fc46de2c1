//! # sss-scene: the scene format of the subsurface-scattering toolkit
//!
//! Parses, loads and validates scene files without the renderer: use it to check a scene, to
//! write a tool that reads our scenes, or as the input stage of your own renderer. The renderer
//! (`sss-render`) takes the [`Scene`] this crate produces.
//!
//! A [`Scene`] is plain data in world space: a pinhole [`Camera`], [`Light`]s, [`Material`]s and
//! [`Object`]s whose triangle meshes are already transformed, cleaned (degenerate triangles
//! dropped and counted) and given per-vertex shading normals. The file format (TOML) is
//! documented in `scenes/README.md`; [`load()`] reads it, [`load_str`] parses text, [`builtin`]
//! returns the scenes embedded in the crate and [`load_named`] takes either, as `sss render` does. Every problem is a [`SceneError`] naming the file,
//! the line and the key; loading never panics on bad input.
//!
//! Units: lengths in scene units; each translucent material says how many scene units make a
//! millimetre ([`Translucent::units_per_mm`]), since the models work in mm.
//!
//! ```
//! use sss_scene::{LoadOptions, builtin, load_str};
//!
//! let scene = builtin("sphere", &LoadOptions::default())?;
//! assert!((0..scene.objects.len()).any(|o| scene.translucent(o).is_some()));
//!
//! // A malformed file is an error naming the problem, never a panic.
//! let err = load_str("[camera]\nresolution = [0, 10]\n", "bad.toml", None, &LoadOptions::default())
//!     .unwrap_err();
//! assert!(err.to_string().contains("bad.toml"));
//! # Ok::<(), sss_scene::SceneError>(())
//! ```
//!
//! ## Papers
//! None of its own; the bumpy-sphere displacement and noise textures use Perlin's improved noise
//! (Perlin 2002), the material presets come from Jensen et al. 2001 (via `sss-bssrdf`).

#![forbid(unsafe_code)]

mod format;
mod load;
mod shapes;

pub use load::{BUILTIN_SCENES, LoadOptions, builtin, load, load_named, load_str};

use glam::DVec3;
use sss_bssrdf::{Medium, ModelKind, Rgb};
use std::fmt;
use std::path::PathBuf;

/// A loaded, validated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    /// Short name (the file stem, or the built-in scene's name).
    pub name: String,
    /// The file it came from (`None` for scenes built in code).
    pub path: Option<PathBuf>,
    /// The camera.
    pub camera: Camera,
    /// Light sources (at least one).
    pub lights: Vec<Light>,
    /// Materials referenced by objects, by index. Only materials some object uses are kept.
    pub materials: Vec<Material>,
    /// Objects with their world-space meshes.
    pub objects: Vec<Object>,
    /// Non-fatal problems found while loading (dropped triangles, ...), each naming the file.
    pub warnings: Vec<String>,
}

/// A pinhole camera.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Eye position.
    pub position: DVec3,
    /// Point looked at.
    pub target: DVec3,
    /// Up hint (need not be orthogonal to the view direction, must not be parallel to it).
    pub up: DVec3,
    /// Vertical field of view in degrees, in (0, 180).
    pub vfov_deg: f64,
    /// Image width in pixels (≥ 1).
    pub width: u32,
    /// Image height in pixels (≥ 1).
    pub height: u32,
    /// Camera samples per pixel (≥ 1); 1 means the pixel centre, more are stratified jittered
    /// positions.
    pub pixel_samples: u32,
}

/// A light source. Radiometric quantities are linear RGB.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    /// An isotropic point light of radiant intensity `intensity` (W/sr).
    Point {
        /// Position.
        position: DVec3,
        /// Radiant intensity per channel.
        intensity: Rgb,
    },
    /// A distant light: parallel rays travelling along `direction` (unit), giving irradiance
    /// `irradiance` on a surface facing it.
    Directional {
        /// Unit direction the light travels in (from the light towards the scene).
        direction: DVec3,
        /// Irradiance on a surface perpendicular to the rays.
        irradiance: Rgb,
    },
    /// A distant disc of angular radius `half_angle` (radians, in (0, π/2)) centred on
    /// `-direction`, of constant radiance L = E / (π sin² half_angle), so that a surface
    /// facing it with the whole disc above its horizon receives irradiance E = `irradiance`
    /// (the integral of L cos θ over the disc is E times the cosine towards its centre): the
    /// sun with its angular diameter (0.53° seen from the earth), which casts penumbrae where
    /// a [`Light::Directional`] casts hard shadows.
    Sun {
        /// Unit direction the light travels in (from the disc's centre towards the scene).
        direction: DVec3,
        /// Irradiance on a surface perpendicular to `direction`.
        irradiance: Rgb,
        /// Half the angular diameter, radians.
        half_angle: f64,
    },
    /// A one-sided parallelogram emitter `corner + s·edge_u + t·edge_v`, s, t ∈ [0, 1],
    /// emitting constant radiance towards `edge_u × edge_v`.
    Quad {
        /// One corner.
        corner: DVec3,
        /// First edge.
        edge_u: DVec3,
        /// Second edge.
        edge_v: DVec3,
        /// Emitted radiance.
        radiance: Rgb,
    },
    /// Constant radiance from every direction not blocked by the scene.
    Environment {
        /// Radiance.
        radiance: Rgb,
    },
}

/// A solid (3D) procedural texture, evaluated at world-space positions. For a translucent
/// material it modulates the irradiance entering the surface (a pre-scatter texture); for a
/// diffuse material it multiplies the albedo.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    /// A 3D checkerboard of cubes of side `scale`: `a` where ⌊x/s⌋+⌊y/s⌋+⌊z/s⌋ is even, `b`
    /// otherwise.
    Checker {
        /// Cube side (scene units, > 0).
        scale: f64,
        /// First colour.
        a: Rgb,
        /// Second colour.
        b: Rgb,
    },
    /// Stripes of period `period` along the unit axis `axis`: `a` on the first half of each
    /// period, `b` on the second.
    Stripes {
        /// Unit axis.
        axis: DVec3,
        /// Period (scene units, > 0).
        period: f64,
        /// First colour.
        a: Rgb,
        /// Second colour.
        b: Rgb,
    },
    /// Smooth value noise of feature size `scale`, blending `a` (noise 0) to `b` (noise 1);
    /// deterministic for `seed`.
    Noise {
        /// Feature size (scene units, > 0).
        scale: f64,
        /// Seed of the lattice values.
        seed: u64,
        /// Colour at noise 0.
        a: Rgb,
        /// Colour at noise 1.
        b: Rgb,
    },
}

/// A translucent material: a BSSRDF model of a homogeneous medium.
#[derive(Clone, Debug)]
pub struct Translucent {
    /// Which model renders it.
    pub model: ModelKind,
    /// The medium (coefficients in 1/mm).
    pub medium: Medium,
    /// Scene units per millimetre (> 0).
    pub units_per_mm: f64,
    /// Optional pre-scatter albedo texture (values in [0, 1]).
    pub texture: Option<Texture>,
    /// How light enters and leaves the model's profile.
    pub angular: Angular,
    /// The radius (scene units) of the ball whose random walk reshapes the model's profile
    /// (`sss_bssrdf::SphereProfile`), or `None` for the half-space's profile (the default).
    /// The file gives a length or `"auto"`: 3 V/A of the material's objects (their volume
    /// over their area, the radius of a ball for a ball).
    pub sphere_radius: Option<f64>,
    /// `sphere_radius = "local"`: each point's own ball radius, 3/4 of its mean
    /// cosine-weighted chord into the object, the pair's ball the geometric mean of its two
    /// points' (`sss_bssrdf::BallFamily`); `sphere_radius` is then `None`. False by default.
    pub local_radius: bool,
    /// Whether the light entering at an angle leaves ahead of its entry point, as the random
    /// walk says (`sss_bssrdf::EntryDrift`: S times 1 + k(r, θ_i) cos φ), instead of evenly
    /// around it (false, the default).
    pub drift: bool,
    /// Whether the light refracted through the object without a collision is added to the
    /// model's (`unscattered = true`): Beer–Lambert attenuation along the refracted rays
    /// through the real geometry, which no BSSRDF profile carries, most of the light of
    /// strongly absorbing or optically thin media seen against bright light. False by default.
    pub unscattered: bool,
}

/// The angular factors of a radial model, S = W_i(θ_i) R_d(r) W_o(θ_o).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Angular {
    /// W_i = F_t(η, cos θ_i), W_o = F_t(η, cos θ_o)/(cπ) (pbrt 3rd ed. §11.4.2): every model's
    /// own, and the default.
    #[default]
    Fresnel,
    /// The half-space's directional albedo A(θ) from the random walk
    /// (`sss_bssrdf::DirectionalAlbedo`): W_i = F_t(η, 1) A(θ_i)/A(0°), W_o = A(θ_o)/(πĀ), so
    /// that oblique light returns what real transport returns and leaves in its lobe.
    Albedo,
}

impl Angular {
    /// The scene file's name for it.
    pub fn name(self) -> &'static str {
        match self {
            Angular::Fresnel => "fresnel",
            Angular::Albedo => "albedo",
        }
    }
}

/// What a material is.
#[derive(Clone, Debug)]
pub enum MaterialKind {
    /// Subsurface scattering.
    Translucent(Translucent),
    /// Opaque Lambertian reflection.
    Diffuse {
        /// Albedo in [0, 1] per channel.
        albedo: Rgb,
        /// Optional texture multiplying the albedo.
        texture: Option<Texture>,
    },
}

/// A named material.
#[derive(Clone, Debug)]
pub struct Material {
    /// The name objects refer to it by.
    pub name: String,
    /// Its kind and parameters.
    pub kind: MaterialKind,
}

/// A triangle mesh in world space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions (finite).
    pub positions: Vec<DVec3>,
    /// Unit per-vertex shading normals, one per position, pointing out of the object.
    pub normals: Vec<DVec3>,
    /// Triangles as indices into `positions`, counter-clockwise seen from outside; none is
    /// degenerate (zero area).
    pub triangles: Vec<[u32; 3]>,
}

/// The curvature of a procedural shape in closed form, in 1/scene unit after the object's
/// transform (known only under a uniform scale; `None` in [`Object::curvature`] otherwise, and
/// for meshes from files and the bumpy sphere, whose curvature is estimated from the mesh).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Curvature {
    /// The same max(|κ₁|, |κ₂|) everywhere: 1/r on a sphere of radius r; 0 on a plane and on
    /// the faces of a box (its edges are a set of zero area).
    Uniform(f64),
    /// A torus about `axis` through `center`, of major radius `major` and tube radius `minor`:
    /// κ₁ = 1/minor around the tube and κ₂ = cos v / (major + minor cos v) along it, v the
    /// angle around the tube from the outer equator (do Carmo 1976, §3-3, Example 4).
    Torus {
        /// Centre.
        center: DVec3,
        /// Unit axis of revolution.
        axis: DVec3,
        /// Distance from the centre to the tube's centre circle.
        major: f64,
        /// Tube radius.
        minor: f64,
    },
}

impl Curvature {
    /// max(|κ₁|, |κ₂|) at the surface point `p` (finite; a point off the surface is taken
    /// at its angle around the tube).
    pub fn max_abs_at(&self, p: DVec3) -> f64 {
        match *self {
            Curvature::Uniform(k) => k.abs(),
            Curvature::Torus {
                center,
                axis,
                major,
                minor,
            } => {
                let q = p - center;
                let rho = (q - axis * q.dot(axis)).length();
                // cos v = (ρ − R)/r on the surface; κ₂ = cos v/(R + r cos v) = (ρ − R)/(r ρ).
                let k1 = 1.0 / minor;
                let k2 = if rho > 0.0 {
                    ((rho - major) / (minor * rho)).abs()
                } else {
                    k1
                };
                k1.max(k2)
            }
        }
    }
}

/// An object: a mesh with a material.
#[derive(Clone, Debug)]
pub struct Object {
    /// Name (from the file, or `object<N>`).
    pub name: String,
    /// Index into [`Scene::materials`].
    pub material: usize,
    /// World-space geometry (at least one triangle).
    pub mesh: Mesh,
    /// The shape's curvature in closed form, when it is a procedural shape under a uniform
    /// scale (methods that need curvature estimate it from the mesh otherwise).
    pub curvature: Option<Curvature>,
}

/// A problem with a scene file: which file, where in it (line or key, when known), and what.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneError {
    /// The file (or built-in scene name) with the problem.
    pub file: String,
    /// 1-based line, when known.
    pub line: Option<usize>,
    /// The key or path of keys (`objects[2].material`), when known.
    pub key: Option<String>,
    /// What is wrong.
    pub message: String,
    /// What kind of problem: callers skip scenes whose mesh is absent, and fail on the rest.
    pub kind: SceneErrorKind,
}

/// The kind of a [`SceneError`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneErrorKind {
    /// The scene text is malformed or invalid (syntax, unknown key, bad value, bad mesh data).
    Invalid,
    /// A mesh file the scene names was not found in any searched directory.
    MeshNotFound,
    /// A file could not be read.
    Io,
}

impl fmt::Display for SceneError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file)?;
        if let Some(line) = self.line {
            write!(f, ":{line}")?;
        }
        if let Some(key) = &self.key {
            write!(f, ": `{key}`")?;
        }
        write!(f, ": {}", self.message)
    }
}

impl std::error::Error for SceneError {}

impl Texture {
    /// The texture's colour at world-space point `p`; every channel in [0, 1] when the
    /// colours are.
    pub fn eval(&self, p: DVec3) -> Rgb {
        shapes::eval_texture(self, p)
    }
}

impl Scene {
    /// The translucent material of object `i`, if it has one.
    pub fn translucent(&self, object: usize) -> Option<&Translucent> {
        match &self.materials[self.objects[object].material].kind {
            MaterialKind::Translucent(t) => Some(t),
            MaterialKind::Diffuse { .. } => None,
        }
    }

    /// 3 V/A over the objects of material `material` (scene units): the radius of a ball for a
    /// ball, and for another closed shape the radius of the ball with its volume-to-area ratio
    /// (what `sphere_radius = "auto"` takes). `None` when they enclose no volume (open or
    /// inside-out meshes) or the material has no objects.
    pub fn volume_radius(&self, material: usize) -> Option<f64> {
        volume_radius(&self.objects, material)
    }
}

/// [`Scene::volume_radius`] over `objects`.
pub(crate) fn volume_radius(objects: &[Object], material: usize) -> Option<f64> {
    let (mut volume, mut area) = (0.0, 0.0);
    for o in objects.iter().filter(|o| o.material == material) {
        volume += shapes::signed_volume(&o.mesh.positions, &o.mesh.triangles);
        area += shapes::area(&o.mesh.positions, &o.mesh.triangles);
    }
    let radius = 3.0 * volume / area;
    (radius.is_finite() && radius > 0.0).then_some(radius)
}
