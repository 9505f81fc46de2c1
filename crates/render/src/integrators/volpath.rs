//! `volpath`: volumetric path tracing of each translucent object as a closed mesh filled with
//! its homogeneous medium (pbrt 3rd ed. §15.3's volumetric path tracer; the physics of Mitsuba
//! 3's `volpath`/`volpathmis` and of Blender Cycles' random walk). It uses no BSSRDF model:
//! light is followed through the boundary and the medium itself, so its image converges to
//! real light transport in the actual geometry (curvature, thin parts, single scattering, the
//! exit direction), not to a model. That makes it the reference the models are scored
//! against (`cargo xtask compare --truth`), and the brute force users would otherwise run.
//!
//! - The medium: σ_a and σ_s from the material in 1/mm, per scene unit through the material's
//!   `units_per_mm`; g the medium's own (presets give reduced coefficients with g = 0), or
//!   `--g`, which keeps the reduced scattering σ_s' and scatters with σ_s = σ_s'/(1 − g) and
//!   Henyey–Greenstein g, to show the similarity relation's own error
//!   ([`crate::volume::interior`]).
//! - The boundary ([`crate::volume::boundary`]): a smooth dielectric at the material's η (Fresnel reflection
//!   and refraction, total internal reflection), or `--boundary lambertian`, Cycles' random
//!   walk boundary (diffuse transmission in and out, next-event estimation at the exit).
//! - Chromatic media without bias or colour fireflies: distances sampled in one channel per
//!   path, every channel weighted by the balance heuristic over the three channels' path
//!   densities ([`crate::volume::spectral`]).
//! - Lights: a path leaving the objects collects the quad lights it crosses and the
//!   environment ([`crate::volume::emitters`]). A point or directional light cannot be reached through a
//!   smooth dielectric by a unidirectional tracer (its light arrives from one direction that
//!   the refracted ray never samples; Mitsuba 3's image is black there too): such a scene is
//!   refused with an error naming `--boundary lambertian`, which reaches them by next-event
//!   estimation, never rendered silently black.
//! - Scattering orders: `--scattering single`, `multiple` or `unscattered` keeps only the
//!   light whose path collided once, two times or more, or never in the media
//!   ([`Scattering`]), so the share of each order in real transport can be measured (`cargo
//!   xtask compare --deficit`).
//! - Light traded between translucent surfaces: `--reentry no` ends a path where, having left
//!   a medium, it meets a translucent surface, so the image holds only the light a BSSRDF
//!   under direct light can carry; the difference from `yes` is the interreflection between
//!   the objects' parts (concave folds, facing surfaces).
//! - The rest of the scene (diffuse surfaces, their shadows, the background) is lit as for
//!   every method, by `render`'s direct light, so whole images compare.
//!
//! The value of a G-buffer sample is the mean of `--spp` paths from it (each path is one
//! estimate; [`crate::volume::walk`]); the per-pixel standard error follows from their spread. Every path
//! is seeded by its G-buffer sample, so images are bit-identical for any thread count.

pub use crate::volume::boundary::Boundary;
pub use crate::volume::walk::Scattering;

use super::{
    Converges, Integrator, Method, MethodOptions, OptionKind, OptionSpec, Shaded, Stat, Sweep,
    mean_and_variance, pixel_std_error,
};
use crate::Error;
use crate::frame::Frame;
use crate::progress::Progress;
use crate::rng::{Stream, rng};
use crate::volume::emitters::Emitters;
use crate::volume::interior;
use crate::volume::walk::{WalkCounts, Walker};
use rayon::prelude::*;
use sss_bssrdf::Rgb;
use sss_scene::{Light, Scene};

/// The options of `volpath`.
pub const OPTIONS: [OptionSpec; 6] = [
    OptionSpec {
        name: "spp",
        value_name: "N",
        default: "64",
        help: "Paths per pixel sample",
        kind: OptionKind::Value,
        values: &[],
    },
    OptionSpec {
        name: "boundary",
        value_name: "KIND",
        default: "dielectric",
        help: "How light crosses the translucent surfaces: a smooth dielectric at the material's \
               eta (quad and environment lights only), or Cycles' random-walk boundary \
               (Lambertian in and out, every light)",
        kind: OptionKind::Value,
        values: &["dielectric", "lambertian"],
    },
    OptionSpec {
        name: "g",
        value_name: "G",
        default: "material",
        help: "Henyey-Greenstein anisotropy of the walk: `material` (the medium's own), or a \
               value in (-1, 1) that keeps the reduced scattering and scatters with \
               sigma_s = sigma_s'/(1 - g)",
        kind: OptionKind::Value,
        values: &[],
    },
    OptionSpec {
        name: "max-events",
        value_name: "N",
        default: "none",
        help: "Collisions and boundary events per path before it is stopped (`none`: no cap; a \
               cap darkens the image, counted in the stat capped_paths)",
        kind: OptionKind::Value,
        values: &[],
    },
    OptionSpec {
        name: "scattering",
        value_name: "ORDERS",
        default: "all",
        help: "Which light the image holds, by the collisions of its path in the media: `all`, \
               `single` (exactly one collision), `multiple` (two or more) or `unscattered` \
               (none: light refracted through the media and out again)",
        kind: OptionKind::Value,
        values: &["all", "single", "multiple", "unscattered"],
    },
    OptionSpec {
        name: "reentry",
        value_name: "YES|NO",
        default: "yes",
        help: "Whether light that left a translucent surface and met one again counts (`no`: \
               a path ends where, leaving a medium, it meets a translucent surface, so the \
               image holds no light traded between the objects' parts, as a BSSRDF under \
               direct light)",
        kind: OptionKind::Value,
        values: &["yes", "no"],
    },
];

/// The registry entry.
pub const METHOD: Method = Method {
    name: "volpath",
    about: "Volumetric path tracing of the media in the meshes: real light transport, no \
            BSSRDF model (pbrt §15.3)",
    options: &OPTIONS,
    build: |o| Ok(Box::new(VolPath::from_options(o)?)),
    sweep: Sweep {
        option: "spp",
        label: "spp",
        values: |quick| {
            if quick {
                vec![4.0, 16.0, 64.0]
            } else {
                vec![4.0, 16.0, 64.0, 256.0, 1024.0]
            }
        },
    },
    converges_to: Converges::Transport,
};

/// Option `name`'s value: None for `keyword`, else the value parsed as a `T`.
fn keyword_or<T: std::str::FromStr>(
    o: &MethodOptions,
    name: &str,
    keyword: &str,
) -> Result<Option<T>, Error> {
    let text: String = o.get(&OPTIONS, name)?;
    if text == keyword {
        return Ok(None);
    }
    text.parse().map(Some).map_err(|_| {
        Error::Input(format!(
            "--{name}: `{text}` is neither `{keyword}` nor a {}",
            if keyword == "none" {
                "whole number"
            } else {
                "number"
            }
        ))
    })
}

/// The `volpath` integrator and its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolPath {
    /// Paths per G-buffer sample (≥ 1).
    pub spp: u32,
    /// How light crosses the translucent surfaces.
    pub boundary: Boundary,
    /// Henyey–Greenstein g of the walk (None: the medium's own).
    pub g: Option<f64>,
    /// Events per path before it is stopped (None: no cap).
    pub max_events: Option<u64>,
    /// Which scattering orders the image holds.
    pub scattering: Scattering,
    /// Whether light that left a translucent surface and met one again counts
    /// (interreflection between translucent surfaces).
    pub reentry: bool,
}

impl Default for VolPath {
    /// The settings of the declared defaults of [`OPTIONS`].
    fn default() -> Self {
        crate::integrators::options::from_declared(METHOD.name, VolPath::from_options)
    }
}

impl VolPath {
    /// The settings `options` describe.
    pub fn from_options(o: &MethodOptions) -> Result<Self, Error> {
        let spp: u32 = o.get(&OPTIONS, "spp")?;
        if spp == 0 {
            return Err(Error::Input("--spp must be at least 1".into()));
        }
        let boundary = match o.get::<String>(&OPTIONS, "boundary")?.as_str() {
            "dielectric" => Boundary::Dielectric,
            "lambertian" => Boundary::Lambertian,
            other => {
                return Err(Error::Input(format!(
                    "--boundary: `{other}` is not one of dielectric, lambertian"
                )));
            }
        };
        let g = keyword_or::<f64>(o, "g", "material")?;
        if let Some(g) = g
            && !(g.is_finite() && g.abs() < 1.0)
        {
            return Err(Error::Input(format!(
                "--g must lie strictly between -1 and 1, got {g}"
            )));
        }
        let max_events = keyword_or::<u64>(o, "max-events", "none")?;
        if max_events == Some(0) {
            return Err(Error::Input(
                "--max-events must be at least 1 (or `none`)".into(),
            ));
        }
        let scattering = match o.get::<String>(&OPTIONS, "scattering")?.as_str() {
            "all" => Scattering::All,
            "single" => Scattering::Single,
            "multiple" => Scattering::Multiple,
            "unscattered" => Scattering::Unscattered,
            other => {
                return Err(Error::Input(format!(
                    "--scattering: `{other}` is not one of all, single, multiple, unscattered"
                )));
            }
        };
        let reentry = match o.get::<String>(&OPTIONS, "reentry")?.as_str() {
            "yes" => true,
            "no" => false,
            other => {
                return Err(Error::Input(format!(
                    "--reentry: `{other}` is not one of yes, no"
                )));
            }
        };
        Ok(VolPath {
            spp,
            boundary,
            g,
            max_events,
            scattering,
            reentry,
        })
    }

    /// Refuses a scene whose lights a smooth dielectric boundary cannot reach.
    pub fn check_lights(&self, scene: &Scene) -> Result<(), Error> {
        if self.boundary != Boundary::Dielectric {
            return Ok(());
        }
        for (i, l) in scene.lights.iter().enumerate() {
            let kind = match l {
                Light::Point { .. } => "point",
                Light::Directional { .. } => "directional",
                _ => continue,
            };
            return Err(Error::Unsupported(format!(
                "scene `{}`: light {i} is a {kind} light, which a path tracer cannot reach \
                 through a smooth dielectric boundary (the image would miss its light); use \
                 --boundary lambertian, which reaches it by next-event estimation, or a quad, \
                 sun or environment light",
                scene.name
            )));
        }
        Ok(())
    }
}

impl Integrator for VolPath {
    fn name(&self) -> &'static str {
        METHOD.name
    }

    fn describe(&self) -> String {
        format!(
            "paths per pixel sample: {}, boundary {}, g {}, max events {}, scattering {}, \
             reentry {}",
            self.spp,
            self.boundary.name(),
            self.g
                .map_or("of the material".to_string(), |g| g.to_string()),
            self.max_events
                .map_or("none".to_string(), |n| n.to_string()),
            self.scattering.name(),
            if self.reentry { "yes" } else { "no" }
        )
    }

    fn follows_media(&self) -> bool {
        true
    }

    fn integrate(&self, frame: &Frame<'_>, progress: &dyn Progress) -> Result<Shaded, Error> {
        let scene = frame.scene;
        self.check_lights(scene)?;
        let t = std::time::Instant::now();
        let interiors = interior::interiors(scene, self.g)?;
        let emitters = Emitters::new(&scene.lights);
        let walker = Walker {
            scene,
            geom: &frame.geom,
            interiors: &interiors,
            emitters: &emitters,
            boundary: self.boundary,
            max_events: self.max_events,
            scattering: self.scattering,
            reentry: self.reentry,
        };
        let spp = self.spp.max(1);
        let gspp = frame.gbuffer.samples_per_pixel as u64;
        let results: Vec<(Rgb, Rgb, WalkCounts)> = frame
            .gbuffer
            .samples
            .par_iter()
            .map_init(Vec::new, |packets, g| {
                progress.advance(1);
                let mut counts = WalkCounts::default();
                if frame.shading_of(g.object).is_none() {
                    return ([0.0; 3], [0.0; 3], counts);
                }
                let mut r = rng(
                    frame.seed,
                    Stream::Volume,
                    g.pixel as u64 * gspp + g.index as u64,
                );
                let mut sum = [0.0; 3];
                let mut sum2 = [0.0; 3];
                for _ in 0..spp {
                    let v = walker.radiance(g, &mut r, &mut counts, packets);
                    for c in 0..3 {
                        sum[c] += v[c];
                        sum2[c] += v[c] * v[c];
                    }
                }
                let (mean, var) = mean_and_variance(sum, sum2, spp);
                (mean, var, counts)
            })
            .collect();
        frame.record("shading", t.elapsed().as_secs_f64());
        let mut counts = WalkCounts::default();
        for r in &results {
            counts.add(&r.2);
        }
        if counts.capped > 0 {
            frame.warn(format!(
                "volpath: {} of {} paths reached --max-events {} and were stopped, which \
                 darkens the image; raise --max-events or set it to none",
                counts.capped,
                counts.paths,
                self.max_events.unwrap_or(0)
            ));
        }
        if counts.lost as f64 > 1e-3 * counts.paths as f64 {
            frame.warn(format!(
                "volpath: {} of {} paths were lost (a walk found no surface of its object \
                 ahead): are the translucent meshes closed?",
                counts.lost, counts.paths
            ));
        }
        let values: Vec<Rgb> = results.iter().map(|r| r.0).collect();
        let variances: Vec<Rgb> = results.iter().map(|r| r.1).collect();
        let std_error = pixel_std_error(&frame.gbuffer, &variances);
        let per_path = |n: u64| n as f64 / (counts.paths.max(1)) as f64;
        Ok(Shaded {
            values,
            std_error: Some(std_error),
            stats: vec![
                Stat {
                    name: "paths",
                    value: counts.paths as f64,
                },
                Stat {
                    name: "collisions_per_path",
                    value: per_path(counts.collisions),
                },
                Stat {
                    name: "interfaces_per_path",
                    value: per_path(counts.interfaces),
                },
                Stat {
                    name: "lost_paths",
                    value: counts.lost as f64,
                },
                Stat {
                    name: "capped_paths",
                    value: counts.capped as f64,
                },
            ],
            layers: Vec::new(),
        })
    }
}
