//! The single-tree traversal of Jensen & Buhler 2002 ("A rapid hierarchical rendering
//! technique for translucent materials", §4), as Algorithm 1 of Milaenen et al. 2019 states
//! it: at every shading point x_o, walk a kd-tree over the object's irradiance samples
//! ([`sss_hierarchy::IrradianceTree`]) and let a node stand for all its samples when it
//! subtends a small solid angle, Δω = A_I / ‖x_o − p_I‖² < ε, and x_o is outside its bounding
//! box (the traversal is the family's, in its parent module: the bounces of
//! [`super::interreflection`] evaluate the exitance with it too).
//!
//! The contribution of an accepted node is R_d(‖x_o − p_I‖) Σ E_i A_i (its flux at its
//! irradiance-weighted position); a leaf that is not accepted adds its samples one by one,
//! exactly as [`super::exact`] does (the same
//! [`crate::shading::TranslucentShading::rd_sample_scene`]). So at ε → 0 the traversal equals
//! `exact` over the same samples to rounding, and its error against `exact` is the
//! hierarchy's error alone. The test is applied to leaves too (as in Mitsuba's `irrtree`): a
//! distant leaf is one evaluation, not `leaf` evaluations.
//!
//! Radial models only (a node's flux is summed without incident directions): the directional
//! dipole and drifting materials are refused with an error naming the material. A material
//! that gives each point its own ball (`sphere_radius = "local"`, [`crate::local_radius`]) is
//! summed with each pair's ball: a node stands for its samples only where their radii spread
//! by at most [`super::BALL_SPREAD`] (its ball their geometric mean), and a leaf sums each pair
//! with its own, so at ε → 0 the traversal still equals `exact`.

use super::{
    Counts, LitSamples, ball_outputs, eps_sweep, illumination_tree_bytes, illumination_trees,
    lit_samples, single, tree_balls,
};
use crate::Error;
use crate::frame::Frame;
use crate::integrators::Converges;
use crate::integrators::options::{
    BOUNCES, MAX_SAMPLES, SOLID_ANGLE, SPACING, declared, eps_option, sample_settings,
};
use crate::integrators::{
    Integrator, Method, MethodOptions, OptionSpec, Shaded, Sweep, add_weighted, check_radial_balls,
};
use crate::irradiance::IrradianceSettings;
use crate::progress::Progress;
use rayon::prelude::*;
use sss_bssrdf::Rgb;
use sss_scene::Scene;

/// The options: the irradiance-sample options and ε.
pub const OPTIONS: [OptionSpec; 4] = [SPACING, MAX_SAMPLES, BOUNCES, SOLID_ANGLE];

/// The registry entry.
pub const METHOD: Method = Method {
    name: "single-tree",
    about: "Jensen & Buhler 2002 hierarchical point sum (one tree over irradiance samples)",
    options: &OPTIONS,
    build: |o| Ok(Box::new(SingleTree::from_options(o)?)),
    sweep: Sweep {
        option: "solid-angle",
        label: "solid_angle",
        values: eps_sweep,
    },
    converges_to: Converges::Model,
};

/// The `single-tree` integrator and its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SingleTree {
    /// Irradiance sample placement and lighting.
    pub irradiance: IrradianceSettings,
    /// The solid-angle threshold ε.
    pub eps: f64,
}

impl Default for SingleTree {
    fn default() -> Self {
        SingleTree {
            irradiance: IrradianceSettings::default(),
            eps: declared(&OPTIONS, "solid-angle"),
        }
    }
}

impl SingleTree {
    /// The settings `options` describe.
    pub fn from_options(o: &MethodOptions) -> Result<Self, Error> {
        Ok(SingleTree {
            irradiance: sample_settings(o)?,
            eps: eps_option(o, &OPTIONS, "solid-angle")?,
        })
    }
}

impl Integrator for SingleTree {
    fn name(&self) -> &'static str {
        METHOD.name
    }

    fn describe(&self) -> String {
        format!(
            "ε = {}, irradiance sample spacing {} mean free paths, at most {} per object",
            self.eps, self.irradiance.spacing_mfp, self.irradiance.max_samples
        )
    }

    fn irradiance_settings(&self) -> Option<IrradianceSettings> {
        Some(self.irradiance)
    }

    fn structure_bytes(&self, _scene: &Scene, samples: &[(usize, u64, u64)]) -> u64 {
        illumination_tree_bytes(samples)
    }

    fn integrate(&self, frame: &Frame<'_>, progress: &dyn Progress) -> Result<Shaded, Error> {
        check_radial_balls(frame, METHOD.name)?;
        let LitSamples {
            samples,
            balls,
            stats: light_stats,
        } = lit_samples(frame, &self.irradiance)?;
        let trees = frame.timed("illumination_tree", || illumination_trees(frame, &samples));
        let tree_balls = tree_balls(&balls, &trees);
        let counts = Counts::default();
        let values: Vec<Rgb> = frame.timed("shading", || {
            frame
                .gbuffer
                .samples
                .par_iter()
                .enumerate()
                .map(|(k, g)| {
                    progress.advance(1);
                    match (frame.shading_of(g.object), &trees[g.object as usize]) {
                        (Some(sh), Some(t)) => {
                            let own = tree_balls[g.object as usize]
                                .as_ref()
                                .map(|b| (b, balls.points.get(k).copied().unwrap_or(f64::NAN)));
                            let sum = single(t, g.p, self.eps, sh, &counts, own);
                            let mut out = [0.0; 3];
                            add_weighted(&mut out, sum, sh.exit_weights(g.n, g.wo));
                            out
                        }
                        _ => [0.0; 3],
                    }
                })
                .collect()
        });
        let mut stats = counts.stats("nodes_visited");
        stats.extend(light_stats);
        let mut layers = Vec::new();
        ball_outputs(frame, &balls, &mut stats, &mut layers);
        Ok(Shaded {
            values,
            stats,
            layers,
            ..Shaded::default()
        })
    }
}
