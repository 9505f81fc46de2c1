//! What `--truth` runs: its scenes (`scenes/experiments/truth-*.toml`), the media and lights
//! each is rendered with, and the [`Plan`] of a full or `--quick` run.

use super::*;

/// A 10 mm sphere under a quad light (1 unit = 1 mm).
pub const SPHERE10: &str = include_str!("../../../../scenes/experiments/truth-sphere10.toml");
/// A 3 mm sphere, the same framing and light scaled by 0.3.
pub const SPHERE3: &str = include_str!("../../../../scenes/experiments/truth-sphere3.toml");
/// The small Stanford bunny at 50 mm.
pub const BUNNY: &str = include_str!("../../../../scenes/experiments/truth-bunny.toml");
/// The Lee Perry-Smith bust at 450 mm.
pub const HEAD: &str = include_str!("../../../../scenes/experiments/truth-head.toml");
/// The Stanford dragon at 140 mm.
pub const DRAGON: &str = include_str!("../../../../scenes/experiments/truth-dragon.toml");

/// A medium of the experiment.
#[derive(Clone, Copy, Debug)]
pub(crate) struct MediumSpec {
    /// Its name in the CSV and the report.
    pub name: &'static str,
    /// Builds it (1/mm, g = 0, η = 1.3).
    pub make: fn() -> Medium,
}

fn preset(name: &str) -> Medium {
    Medium::preset(name).unwrap_or_else(|e| panic!("preset {name}: {e}"))
}

/// Jensen et al. 2001's skin1.
pub const SKIN1: MediumSpec = MediumSpec {
    name: "skin1",
    make: || preset("skin1"),
};
/// Marble: albedo 0.998–0.999, long walks.
pub const MARBLE: MediumSpec = MediumSpec {
    name: "marble",
    make: || preset("marble"),
};
/// Ketchup: red scatters (albedo 0.75), green and blue are absorbed (0.07, 0.02).
pub const KETCHUP: MediumSpec = MediumSpec {
    name: "ketchup",
    make: || preset("ketchup"),
};
/// A grey-ish absorbing medium of albedo 0.44 / 0.40 / 0.35 (σ_a 1.0 / 1.2 / 1.5, σ_s 0.8 per
/// mm): where diffusion is least at home.
pub const ABSORBING: MediumSpec = MediumSpec {
    name: "absorbing",
    make: || {
        Medium::new([1.0, 1.2, 1.5], [0.8; 3], 0.0, 1.3)
            .unwrap_or_else(|e| panic!("absorbing medium: {e}"))
    },
};

/// How a case is lit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Lighting {
    /// The scene file's quad light.
    Quad,
    /// A uniform environment of radiance 1 instead.
    Environment,
}

impl Lighting {
    /// The name in the CSV and the report.
    pub fn name(self) -> &'static str {
        match self {
            Lighting::Quad => "quad",
            Lighting::Environment => "environment",
        }
    }
}

/// One case: a scene file rendered in a medium under a light.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Case {
    /// The scene's short name (`sphere10`, `bunny`, ...).
    pub scene: &'static str,
    /// The scene file's text.
    pub text: &'static str,
    /// The medium every translucent material gets.
    pub medium: MediumSpec,
    /// The light.
    pub lighting: Lighting,
}

impl Case {
    /// `scene-medium-light`, the case's name in file names and tables.
    pub fn name(&self) -> String {
        format!(
            "{}-{}-{}",
            self.scene,
            self.medium.name,
            self.lighting.name()
        )
    }

    /// The scene of the case at `1/shrink` of the file's resolution, every translucent material
    /// in the case's medium with `model`. Errors name the scene file; a missing mesh is
    /// reported as such (the case is then skipped).
    pub fn scene(
        &self,
        model: ModelKind,
        shrink: u32,
        mesh_dirs: &[PathBuf],
    ) -> Result<Scene, SceneError> {
        let opts = LoadOptions {
            mesh_dirs: mesh_dirs.to_vec(),
        };
        let file = format!("truth-{}.toml", self.scene);
        let mut s = scene::load_str(self.text, &file, None, &opts)?;
        s.name = self.name();
        s.camera.width = (s.camera.width / shrink.max(1)).max(1);
        s.camera.height = (s.camera.height / shrink.max(1)).max(1);
        for m in &mut s.materials {
            if let MaterialKind::Translucent(t) = &mut m.kind {
                t.medium = (self.medium.make)();
                t.model = model;
            }
        }
        if self.lighting == Lighting::Environment {
            s.lights = vec![Light::Environment { radiance: [1.0; 3] }];
        }
        Ok(s)
    }
}

/// Gives every translucent material of `scene` the half-space's directional albedo for its
/// angular factors (`angular = "albedo"`).
pub(crate) fn with_albedo_weights(scene: &mut Scene) {
    for m in &mut scene.materials {
        if let MaterialKind::Translucent(t) = &mut m.kind {
            t.angular = Angular::Albedo;
        }
    }
}

/// Gives every translucent material of `scene` the profile of the ball of its objects'
/// volume-to-area ratio (`sphere_radius = "auto"`); materials whose objects enclose no volume
/// keep the half-space's.
pub(crate) fn with_ball_profile(scene: &mut Scene) {
    for m in 0..scene.materials.len() {
        let radius = scene.volume_radius(m);
        if let MaterialKind::Translucent(t) = &mut scene.materials[m].kind {
            t.sphere_radius = radius;
        }
    }
}

/// Gives every translucent material of `scene` each point's own ball instead of one radius
/// (`sphere_radius = "local"`: the chords into the object at each point).
pub(crate) fn with_local_balls(scene: &mut Scene) {
    for m in &mut scene.materials {
        if let MaterialKind::Translucent(t) = &mut m.kind {
            t.sphere_radius = None;
            t.local_radius = true;
        }
    }
}

/// Adds to every translucent material of `scene` the light refracted through its objects
/// without a collision (`unscattered = true`).
pub(crate) fn with_unscattered(scene: &mut Scene) {
    for m in &mut scene.materials {
        if let MaterialKind::Translucent(t) = &mut m.kind {
            t.unscattered = true;
        }
    }
}

/// Gives every translucent material of `scene` the walk's drift of obliquely entering light
/// (`drift = true`).
pub(crate) fn with_drift(scene: &mut Scene) {
    for m in &mut scene.materials {
        if let MaterialKind::Translucent(t) = &mut m.kind {
            t.drift = true;
        }
    }
}

/// What one run of the experiment does.
#[derive(Clone, Debug)]
pub(crate) struct Plan {
    /// The cases, in report order.
    pub cases: Vec<Case>,
    /// The scene files' resolution is divided by this.
    pub shrink: u32,
    /// The reference's relative noise to aim for (its RMS standard error over the translucent
    /// pixels and channels, over its mean).
    pub reference_noise: f64,
    /// Paths per pixel of the reference's pilot, and the most it may take.
    pub reference_spp: (u32, u32),
    /// `volpath`'s own sweep: paths per pixel.
    pub volpath_spp: Vec<u32>,
    /// Whether the fast methods (`dual-tree-fmm`, `manylight`, `separable`) run their sweeps.
    pub fast: bool,
    /// Mitsuba's samples per pixel (`--peers`).
    pub peer_spp: Vec<u32>,
    /// Cycles' samples per pixel, in each of its modes (`--peers`).
    pub cycles_spp: Vec<u32>,
}

/// The plan of a full run (about an hour on 2 cores) or of `--quick` (the 10 mm skin1 sphere
/// under its quad light at half resolution, in about 20 seconds). The references' noise
/// targets (4 %, 8 % with `--quick`) sit well below the models' errors against them (25 % and
/// more in relative RMSE on the skin sphere), and their noise is removed from every score.
pub(crate) fn plan(quick: bool) -> Plan {
    let case = |scene, text, medium, lighting| Case {
        scene,
        text,
        medium,
        lighting,
    };
    use Lighting::{Environment as Env, Quad};
    if quick {
        return Plan {
            cases: vec![case("sphere10", SPHERE10, SKIN1, Quad)],
            shrink: 2,
            reference_noise: 0.08,
            reference_spp: (16, 4096),
            volpath_spp: vec![1, 4, 16, 64],
            fast: true,
            peer_spp: vec![16, 64],
            cycles_spp: vec![16, 64],
        };
    }
    Plan {
        cases: vec![
            case("sphere10", SPHERE10, SKIN1, Quad),
            case("sphere10", SPHERE10, MARBLE, Quad),
            case("sphere10", SPHERE10, KETCHUP, Quad),
            case("sphere10", SPHERE10, ABSORBING, Quad),
            case("sphere10", SPHERE10, SKIN1, Env),
            case("sphere3", SPHERE3, SKIN1, Quad),
            case("sphere3", SPHERE3, MARBLE, Env),
            case("bunny", BUNNY, SKIN1, Quad),
            case("bunny", BUNNY, KETCHUP, Env),
            case("head", HEAD, SKIN1, Quad),
            case("head", HEAD, SKIN1, Env),
            case("dragon", DRAGON, SKIN1, Quad),
            case("dragon", DRAGON, MARBLE, Env),
        ],
        shrink: 1,
        reference_noise: 0.04,
        reference_spp: (16, 65536),
        volpath_spp: vec![1, 4, 16, 64, 256],
        fast: true,
        peer_spp: vec![16, 64, 256, 1024],
        cycles_spp: vec![16, 64, 256],
    }
}
