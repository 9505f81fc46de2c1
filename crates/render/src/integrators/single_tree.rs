//! The single-tree traversal of Jensen & Buhler 2002 ("A rapid hierarchical rendering
//! technique for translucent materials", §4), as Algorithm 1 of Milaenen et al. 2019 states
//! it: at every shading point x_o, walk a kd-tree over the object's irradiance samples
//! ([`IrradianceTree`]) and let a node stand for all its samples when it subtends a small
//! solid angle, Δω = A_I / ‖x_o − p_I‖² < ε, and x_o is outside its bounding box.
//!
//! The contribution of an accepted node is R_d(‖x_o − p_I‖) Σ E_i A_i (its flux at its
//! irradiance-weighted position); a leaf that is not accepted adds its samples one by one,
//! exactly as [`super::exact`] does (the same [`TranslucentShading::rd_sample_scene`]). So at
//! ε → 0 the traversal equals `exact` over the same samples to rounding, and its error
//! against `exact` is the hierarchy's error alone. The test is applied to leaves too (as in
//! Mitsuba's `irrtree`): a distant leaf is one evaluation, not `leaf` evaluations.
//!
//! Radial models only (a node's flux is summed without incident directions): the directional
//! dipole is refused with an error naming the material.

use super::exact::{SAMPLE_OPTIONS, sample_settings};
use super::{
    Integrator, Method, MethodOptions, OptionKind, OptionSpec, Shaded, Stat, Sweep, add_scaled,
};
use crate::Error;
use crate::frame::Frame;
use crate::irradiance::{IrradianceSettings, ObjectSamples};
use crate::progress::Progress;
use crate::shading::TranslucentShading;
use glam::DVec3;
use rayon::prelude::*;
use sss_bssrdf::Rgb;
use sss_hierarchy::{IrradiancePoint, IrradianceTree, KdNode};
use sss_scene::Scene;
use std::sync::atomic::{AtomicU64, Ordering};

/// Irradiance samples per leaf of the illumination tree. Small, because a leaf that is not
/// accepted is summed sample by sample; the solid-angle test on leaves keeps distant leaves
/// at one evaluation.
pub const ILLUMINATION_LEAF: usize = 4;

/// The options: the irradiance-sample options and ε.
pub const OPTIONS: [OptionSpec; 3] = [
    SAMPLE_OPTIONS[0],
    SAMPLE_OPTIONS[1],
    OptionSpec {
        name: "eps",
        value_name: "E",
        default: "0.05",
        help: "Solid-angle threshold ε: a node of irradiance samples stands for all of them \
               when A / d² < ε (smaller is more accurate and slower)",
        kind: OptionKind::Value,
        values: &[],
    },
];

/// The ε values `cargo xtask compare` sweeps, cheapest first (Milaenen et al. Fig. 6 spans
/// [0.01, 0.2]; three points of it keep the default run near 20 minutes, and
/// `cargo xtask compare --trees` sweeps it finely at paper scale).
pub fn eps_sweep(quick: bool) -> Vec<f64> {
    if quick {
        vec![0.2, 0.05]
    } else {
        vec![0.2, 0.05, 0.01]
    }
}

/// The registry entry.
pub const METHOD: Method = Method {
    name: "single-tree",
    about: "Jensen & Buhler 2002 hierarchical point sum (one tree over irradiance samples)",
    options: &OPTIONS,
    build: |o| Ok(Box::new(SingleTree::from_options(o)?)),
    sweep: Sweep {
        option: "eps",
        label: "eps",
        values: eps_sweep,
    },
};

/// Reads and checks ε (finite, ≥ 0).
pub fn eps_option(o: &MethodOptions, options: &[OptionSpec]) -> Result<f64, Error> {
    let eps: f64 = o.get(options, "eps")?;
    if !(eps.is_finite() && eps >= 0.0) {
        return Err(Error::Input(format!(
            "--eps must be finite and >= 0, got {eps}"
        )));
    }
    Ok(eps)
}

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
            eps: 0.05,
        }
    }
}

impl SingleTree {
    /// The settings `options` describe.
    pub fn from_options(o: &MethodOptions) -> Result<Self, Error> {
        Ok(SingleTree {
            irradiance: sample_settings(o)?,
            eps: eps_option(o, &OPTIONS)?,
        })
    }
}

/// Work counters shared by the tree traversals (summed over threads; integer sums, so the
/// totals do not depend on the thread count).
#[derive(Default)]
pub(crate) struct Counts {
    /// Nodes (or node pairs) visited.
    pub visits: AtomicU64,
    /// Evaluations of R_d for a whole node.
    pub cluster_evals: AtomicU64,
    /// Evaluations of R_d for one irradiance sample.
    pub sample_evals: AtomicU64,
}

impl Counts {
    pub(crate) fn add(&self, visits: u64, clusters: u64, samples: u64) {
        self.visits.fetch_add(visits, Ordering::Relaxed);
        self.cluster_evals.fetch_add(clusters, Ordering::Relaxed);
        self.sample_evals.fetch_add(samples, Ordering::Relaxed);
    }

    pub(crate) fn stats(&self, visit_name: &'static str) -> Vec<Stat> {
        vec![
            Stat {
                name: visit_name,
                value: self.visits.load(Ordering::Relaxed) as f64,
            },
            Stat {
                name: "cluster_evaluations",
                value: self.cluster_evals.load(Ordering::Relaxed) as f64,
            },
            Stat {
                name: "sample_evaluations",
                value: self.sample_evals.load(Ordering::Relaxed) as f64,
            },
        ]
    }
}

/// Errors unless every visible translucent material is radial.
pub(crate) fn check_radial(frame: &Frame<'_>, method: &str) -> Result<(), Error> {
    for &o in &frame.visible {
        if let Some(sh) = frame.shading_of(o) {
            sh.radial(method)?;
        }
    }
    Ok(())
}

/// One illumination tree per visible translucent object, indexed by object.
pub(crate) fn illumination_trees(
    frame: &Frame<'_>,
    samples: &[ObjectSamples],
) -> Vec<Option<IrradianceTree>> {
    let by_object = frame.samples_by_object(samples);
    by_object
        .par_iter()
        .map(|s| {
            s.map(|s| {
                let points: Vec<IrradiancePoint> = s
                    .samples
                    .iter()
                    .map(|p| IrradiancePoint {
                        position: p.position,
                        area: p.area,
                        irradiance: p.irradiance,
                    })
                    .collect();
                IrradianceTree::build(&points, ILLUMINATION_LEAF)
            })
        })
        .collect()
}

/// Bytes of the illumination trees for the per-object sample estimates of
/// [`crate::budget::irradiance_estimate`].
pub(crate) fn illumination_tree_bytes(samples: &[(usize, u64, u64)]) -> u64 {
    samples.iter().fold(0u64, |a, e| {
        a.saturating_add(IrradianceTree::bytes_for(
            usize::try_from(e.1).unwrap_or(usize::MAX / 2),
            ILLUMINATION_LEAF,
        ))
    })
}

/// Δω = A / d² < ε (written without a division, so d = 0 never accepts).
#[inline]
pub(crate) fn accepts(area: f64, d2: f64, eps: f64) -> bool {
    area < eps * d2
}

/// True if `x` is inside the node's (closed) bounding box.
#[inline]
pub(crate) fn inside(node: &KdNode<3>, x: DVec3) -> bool {
    (0..3).all(|k| node.lo[k] <= x[k] && x[k] <= node.hi[k])
}

/// Adds the point sum of `points` at `x` to `acc`
/// ([`TranslucentShading::add_point_sum`], as `exact` sums).
#[inline]
pub(crate) fn add_samples(
    acc: &mut Rgb,
    points: &[IrradiancePoint],
    x: DVec3,
    sh: &TranslucentShading,
) {
    sh.add_point_sum(
        acc,
        x,
        points.iter().map(|p| (p.position, p.area, p.irradiance)),
    );
}

/// The sum at `x` over the tree, by Algorithm 1 (before the exit weight).
pub(crate) fn single(
    tree: &IrradianceTree,
    x: DVec3,
    eps: f64,
    sh: &TranslucentShading,
    counts: &Counts,
) -> Rgb {
    let mut acc = [0.0; 3];
    if tree.tree.nodes.is_empty() {
        return acc;
    }
    let (mut visits, mut clusters, mut singles) = (0u64, 0u64, 0u64);
    let mut stack: Vec<u32> = Vec::with_capacity(64);
    stack.push(0);
    while let Some(k) = stack.pop() {
        visits += 1;
        let node = &tree.tree.nodes[k as usize];
        let cl = &tree.clusters[k as usize];
        let d2 = (cl.position - x).length_squared();
        if accepts(cl.area, d2, eps) && !inside(node, x) {
            let rd = sh.rd_sample_scene(d2.sqrt(), cl.area);
            add_scaled(&mut acc, rd_times(rd, cl.flux), 1.0);
            clusters += 1;
        } else if node.is_leaf() {
            let points = tree.points_of(node);
            add_samples(&mut acc, points, x, sh);
            singles += points.len() as u64;
        } else {
            // Right first, so the left subtree is summed first.
            stack.push(node.right);
            stack.push(node.left);
        }
    }
    counts.add(visits, clusters, singles);
    acc
}

/// rd ⊙ flux.
#[inline]
pub(crate) fn rd_times(rd: Rgb, flux: [f64; 3]) -> Rgb {
    [rd[0] * flux[0], rd[1] * flux[1], rd[2] * flux[2]]
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
        check_radial(frame, METHOD.name)?;
        let samples = frame.irradiance_samples(&self.irradiance);
        let trees = frame.timed("illumination_tree", || illumination_trees(frame, &samples));
        let counts = Counts::default();
        let values: Vec<Rgb> = frame.timed("shading", || {
            frame
                .gbuffer
                .samples
                .par_iter()
                .map(|g| {
                    let v = match (frame.shading_of(g.object), &trees[g.object as usize]) {
                        (Some(sh), Some(t)) => {
                            let sum = single(t, g.p, self.eps, sh, &counts);
                            let mut out = [0.0; 3];
                            add_scaled(&mut out, sum, sh.exit_weight(g.n, g.wo));
                            out
                        }
                        _ => [0.0; 3],
                    };
                    progress.advance(1);
                    v
                })
                .collect()
        });
        Ok(Shaded {
            values,
            stats: counts.stats("nodes_visited"),
            ..Shaded::default()
        })
    }
}
