//! The controlled set-ups of `--deficit`: a flat block (a half-space for the light that
//! reaches the camera) under a small sun at an incidence angle or a uniform environment, seen
//! at an exit angle; slabs of finite thickness lit from behind or from the front; and the
//! truth experiment's scenes with their objects scaled (the medium kept in millimetres), so
//! that only the size of the object against the mean free path changes.

use super::super::plan::{
    BUNNY, Case, DRAGON, KETCHUP, Lighting, MARBLE, MediumSpec, SKIN1, SPHERE10,
};
use super::*;

/// The camera's distance to the flat block's centre, mm.
pub const FLAT_DISTANCE: f64 = 60.0;
/// Its vertical field of view, degrees: a patch about 20 mm across at the block's centre
/// (77 mm long at 75° from the normal), far from the block's 400 mm wide edges.
pub const FLAT_FOV: f64 = 20.0;
/// The sun's angular diameter, degrees: incidence within ±10° of the named angle. A smaller
/// disc is reached by fewer of `volpath`'s paths (its light comes only through the disc).
pub const SUN_DIAMETER: f64 = 20.0;

/// How a flat set-up is lit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum FlatLight {
    /// The sun, its centre at this angle from the normal (degrees), in the plane across the
    /// camera's (so that neither lies in the other's way).
    Sun(f64),
    /// A uniform environment of radiance 1 (every incidence at once).
    Environment,
    /// A 400 mm square quad light 50 mm behind the block's back face (transmission only).
    Behind,
}

/// What a set-up renders.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Kind {
    /// The front face of a block 400 × 400 mm wide, `thickness` mm deep (100: a half-space for
    /// skin's mean free paths of 0.7–1.3 mm), seen from [`FLAT_DISTANCE`] at `view` degrees
    /// from its normal.
    Flat {
        light: FlatLight,
        view: f64,
        thickness: f64,
    },
    /// A cylinder of radius `radius` mm under the uniform environment: the outer side of a
    /// torus whose ring is ten tube radii (the surface across the tube curves like the
    /// cylinder's, along it 11 times less), seen from six tube radii away.
    Cylinder { radius: f64 },
    /// A scene of the truth experiment with its objects `scale` times larger: every
    /// translucent material's units per mm divided by `scale`, so the mean free paths in
    /// scene units shrink instead, with the camera and the lights where they are.
    Scaled {
        scene: &'static str,
        text: &'static str,
        lighting: Lighting,
        scale: f64,
    },
}

/// One row of the experiment.
#[derive(Clone, Debug)]
pub(crate) struct Setup {
    /// The sweep it belongs to (`incidence`, `exit-sun`, ...).
    pub group: &'static str,
    /// The swept quantity and its value.
    pub param: &'static str,
    pub value: f64,
    /// The medium.
    pub medium: MediumSpec,
    /// The scene.
    pub kind: Kind,
}

impl Setup {
    /// Whether light leaving the object can meet it again from outside (interreflection
    /// between its parts): the scaled meshes, which have concave parts. The flat set-ups (a
    /// box), the cylinder and the sphere are convex, so their truth holds no light traded
    /// between surfaces (`volpath --reentry no` equals `volpath` there, tested on a sphere).
    pub fn trades_light(&self) -> bool {
        matches!(self.kind, Kind::Scaled { scene, .. } if scene != "sphere10")
    }

    /// `group-value`, for file names.
    pub fn name(&self) -> String {
        format!("{}-{}-{}", self.group, self.medium.name, self.value)
    }

    /// The scene file of a flat or cylinder set-up (the scaled ones are the truth
    /// experiment's files, changed in memory).
    pub fn text(&self, flat_pixels: u32) -> Option<String> {
        match self.kind {
            Kind::Flat {
                light,
                view,
                thickness,
            } => Some(flat_scene(light, view, thickness, flat_pixels)),
            Kind::Cylinder { radius } => Some(cylinder_scene(radius, flat_pixels)),
            Kind::Scaled { .. } => None,
        }
    }

    /// The scene with `model` on every translucent material, at `1/shrink` of the truth
    /// scenes' resolution (flat set-ups: `flat_pixels` square). Errors name the scene; a
    /// missing mesh is reported as such.
    pub fn scene(
        &self,
        model: ModelKind,
        shrink: u32,
        flat_pixels: u32,
        mesh_dirs: &[PathBuf],
    ) -> Result<Scene, SceneError> {
        let mut s = match self.kind {
            Kind::Flat { .. } | Kind::Cylinder { .. } => {
                let opts = LoadOptions {
                    mesh_dirs: mesh_dirs.to_vec(),
                };
                let text = self.text(flat_pixels).unwrap_or_default();
                let mut s = scene::load_str(&text, &format!("{}.toml", self.name()), None, &opts)?;
                for m in &mut s.materials {
                    if let MaterialKind::Translucent(t) = &mut m.kind {
                        t.medium = (self.medium.make)();
                        t.model = model;
                    }
                }
                s
            }
            Kind::Scaled {
                scene,
                text,
                lighting,
                scale,
            } => {
                // The truth experiment's case (medium, model, light, resolution), scaled.
                let case = Case {
                    scene,
                    text,
                    medium: self.medium,
                    lighting,
                };
                let mut s = case.scene(model, shrink, mesh_dirs)?;
                for m in &mut s.materials {
                    if let MaterialKind::Translucent(t) = &mut m.kind {
                        t.units_per_mm /= scale;
                    }
                }
                s
            }
        };
        s.name = self.name();
        Ok(s)
    }
}

/// The scene file of a flat set-up (1 unit = 1 mm): the block's front face is the plane z = 0,
/// the camera looks at its centre from [`FLAT_DISTANCE`] at `view` degrees (in the x–z plane).
pub(crate) fn flat_scene(light: FlatLight, view: f64, thickness: f64, pixels: u32) -> String {
    let (so, co) = view.to_radians().sin_cos();
    let d = FLAT_DISTANCE;
    let light = match light {
        FlatLight::Sun(incidence) => {
            // Light from (0, sin θ_i, cos θ_i), travelling the other way.
            let (si, ci) = incidence.to_radians().sin_cos();
            format!(
                "[[lights]]\ntype = \"sun\"\ndirection = [0.0, {:?}, {:?}]\nirradiance = 1.0\n\
                 angular_diameter = {SUN_DIAMETER:?}\n",
                -si, -ci
            )
        }
        FlatLight::Environment => {
            "[[lights]]\ntype = \"environment\"\nradiance = 1.0\n".to_string()
        }
        FlatLight::Behind => {
            let z = -thickness - 50.0;
            format!(
                "[[lights]]\ntype = \"quad\"\ncorner = [-200.0, -200.0, {z:?}]\n\
                 edge_u = [400.0, 0.0, 0.0]\nedge_v = [0.0, 400.0, 0.0]\nradiance = 1.0\n"
            )
        }
    };
    format!(
        "# deficit: the front face (z = 0) of a block {thickness} mm deep, seen at {view}° \
         from its normal\n\n\
         [camera]\nposition = [{:?}, 0.0, {:?}]\ntarget = [0.0, 0.0, 0.0]\nfov = {FLAT_FOV:?}\n\
         resolution = [{pixels}, {pixels}]\n\n{light}\n\
         [materials.medium]\ntype = \"translucent\"\nmodel = \"mc-table\"\npreset = \"skin1\"\n\
         units_per_mm = 1.0\n\n\
         [[objects]]\nname = \"block\"\nmaterial = \"medium\"\nshape = \"box\"\n\
         size = [400.0, 400.0, {thickness:?}]\n\
         transform = {{ translate = [0.0, 0.0, {:?}] }}\n",
        d * so,
        d * co,
        -0.5 * thickness
    )
}

/// The scene file of a cylinder set-up: 1 unit = `radius` mm, the torus' tube of radius 1
/// around a ring of radius 10 in the x–z plane, seen at its outer equator (11, 0, 0) from
/// (17, 0, 0), the tube's axis across the image.
pub(crate) fn cylinder_scene(radius: f64, pixels: u32) -> String {
    format!(
        "# deficit: a cylinder of radius {radius} mm (a torus' tube, its ring ten tube radii)\n\n\
         [camera]\nposition = [17.0, 0.0, 0.0]\ntarget = [11.0, 0.0, 0.0]\nfov = 24.0\n\
         resolution = [{pixels}, {pixels}]\n\n\
         [[lights]]\ntype = \"environment\"\nradiance = 1.0\n\n\
         [materials.medium]\ntype = \"translucent\"\nmodel = \"mc-table\"\npreset = \"skin1\"\n\
         units_per_mm = {:?}\n\n\
         [[objects]]\nname = \"cylinder\"\nmaterial = \"medium\"\nshape = \"torus\"\n\
         major = 10.0\nminor = 1.0\nsegments = [1024, 256]\n",
        1.0 / radius
    )
}

/// The set-ups of a full run or of `--quick`, in report order.
pub(crate) fn setups(quick: bool) -> Vec<Setup> {
    let half_space = 100.0;
    let flat = |group, medium, param, value, light, view, thickness| Setup {
        group,
        param,
        value,
        medium,
        kind: Kind::Flat {
            light,
            view,
            thickness,
        },
    };
    let scaled = |group, medium, scene, text, lighting, param, value, scale| Setup {
        group,
        param,
        value,
        medium,
        kind: Kind::Scaled {
            scene,
            text,
            lighting,
            scale,
        },
    };
    let pick =
        |full: &[f64], q: &[f64]| -> Vec<f64> { if quick { q.to_vec() } else { full.to_vec() } };
    let media: Vec<MediumSpec> = if quick {
        vec![SKIN1]
    } else {
        vec![SKIN1, MARBLE, KETCHUP]
    };
    let mut out = Vec::new();
    let angles = pick(&[0.0, 30.0, 45.0, 60.0, 75.0], &[0.0, 60.0]);
    for &m in &media {
        // The half-space head-on (the model's own set-up) in every medium; the sweeps in skin1.
        let incidences: &[f64] = if m.name == SKIN1.name {
            &angles
        } else {
            &[0.0]
        };
        for &a in incidences {
            out.push(flat(
                "incidence",
                m,
                "incidence_deg",
                a,
                FlatLight::Sun(a),
                0.0,
                half_space,
            ));
        }
    }
    for &a in angles.iter().filter(|&&a| a > 0.0) {
        out.push(flat(
            "exit-sun",
            SKIN1,
            "exit_deg",
            a,
            FlatLight::Sun(0.0),
            a,
            half_space,
        ));
    }
    for &m in &media {
        for &a in &angles {
            out.push(flat(
                "exit-environment",
                m,
                "exit_deg",
                a,
                FlatLight::Environment,
                a,
                half_space,
            ));
        }
    }
    for &d in &pick(&[0.5, 1.0, 2.0, 4.0, 8.0], &[1.0]) {
        out.push(flat(
            "slab-behind",
            SKIN1,
            "thickness_mm",
            d,
            FlatLight::Behind,
            0.0,
            d,
        ));
    }
    for &d in &pick(&[0.5, 1.0, 2.0, 4.0, 8.0], &[1.0]) {
        out.push(flat(
            "slab-front",
            SKIN1,
            "thickness_mm",
            d,
            FlatLight::Sun(0.0),
            0.0,
            d,
        ));
    }
    // The 10 mm sphere scaled to these radii; cylinders of the same radii.
    let radii = pick(
        &[2.0, 5.0, 10.0, 20.0, 40.0, 160.0, 640.0],
        &[5.0, 10.0, 160.0],
    );
    for &m in &media {
        for &r in &radii {
            out.push(scaled(
                "sphere-environment",
                m,
                "sphere10",
                SPHERE10,
                Lighting::Environment,
                "radius_mm",
                r,
                r / 10.0,
            ));
        }
    }
    for &r in &radii {
        out.push(Setup {
            group: "cylinder-environment",
            param: "radius_mm",
            value: r,
            medium: SKIN1,
            kind: Kind::Cylinder { radius: r },
        });
    }
    for &r in &radii {
        out.push(scaled(
            "sphere-quad",
            SKIN1,
            "sphere10",
            SPHERE10,
            Lighting::Quad,
            "radius_mm",
            r,
            r / 10.0,
        ));
    }
    if !quick {
        for (group, scene, text) in [
            ("bunny-quad", "bunny", BUNNY),
            ("dragon-quad", "dragon", DRAGON),
        ] {
            for s in [1.0, 4.0, 16.0, 64.0] {
                out.push(scaled(
                    group,
                    SKIN1,
                    scene,
                    text,
                    Lighting::Quad,
                    "scale",
                    s,
                    s,
                ));
            }
        }
    }
    out
}
