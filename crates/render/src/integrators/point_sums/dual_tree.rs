//! The dual-tree traversal of Milaenen et al. 2019 ("Frequency analysis and dual hierarchy for
//! efficient rendering of subsurface scattering", GI 2019, §4.2, Algorithm 2): a kd-tree over
//! the object's irradiance samples ([`IrradianceTree`], as in [`super::single_tree`]) and one
//! over its shading points in screen space ([`PixelTree`]) are walked together, so a cluster
//! of irradiance samples is evaluated once for a cluster of pixels.
//!
//! **DUAL(S, I).** If Δω = A_I / ‖p_S − p_I‖² < ε and the world boxes of S and I are disjoint,
//! SHADE(S, I) with I as one cluster; if both are leaves, SHADE(S, I) with I's samples one by
//! one (the text's "SHADE(S, L)" is a slip for SHADE(S, I), `../shared/docs/wave2.md` F1.0);
//! otherwise split the leaf-free side(s) and recurse.
//!
//! **SHADE(S, I).** S is shaded as one cluster — I's contribution evaluated once at S's mean
//! position and added to all its pixels — when its screen extent LENGTH(S) (pixels) is below
//! P = ρ / max s_p (Eq. 6); otherwise its children are shaded, and a leaf is shaded point by
//! point. (The text's test reads "LENGTH(S) < ρ / BANDWIDTH(S) then split", backwards with
//! respect to its prose and Eq. 6; wave2 F1.0.) I is not refined inside SHADE (the paper's
//! choice).
//!
//! **s_p** per shading point is Eq. 4–5 of the paper through `sss-bandwidth`: the material's
//! B_s and B_θ(θ_o) (computed once per visible material), the distance to the camera, cos θ_o
//! and the curvature k = max(|κ₁|, |κ₂|) interpolated from the mesh's vertices (Rusinkiewicz
//! 2004, standing in for the paper's Kalogerakis et al. 2007) with the hit's barycentric
//! coordinates.
//!
//! **Work split.** The pixel tree is cut into task subtrees of at most [`TASK_ITEMS`] points
//! (a rule of the tree alone, so results do not depend on the thread count), and DUAL(T, root)
//! runs for each task T in parallel. Compared with one DUAL(root, root) this only forgoes
//! accepting pairs above the task level, whose SHADE would refine S below P anyway.
//!
//! At ε → 0 every pair reaches leaf–leaf and with ρ → 0 every point is shaded by itself, so the
//! method then equals `exact` over the same samples to rounding. Radial models only, like the
//! single tree.

pub use super::{PIXEL_LEAF, TASK_ITEMS, curvature_at_hits, pixel_footprint};

use super::{
    Counts, accepts, add_samples, eps_sweep, for_each_dual_object, illumination_tree_bytes,
    illumination_trees, pixel_trees, rd_times, shading_points, task_slices,
};
use super::{LitSamples, lit_samples};
use crate::Error;
use crate::frame::Frame;
use crate::integrators::Converges;
use crate::integrators::options::{
    BOUNCES, MAX_SAMPLES, SOLID_ANGLE, SPACING, declared, eps_option, sample_settings,
};
use crate::integrators::{
    Integrator, Layer, Method, MethodOptions, OptionKind, OptionSpec, Shaded, Stat, Sweep,
    add_scaled, add_weighted, check_radial,
};
use crate::irradiance::IrradianceSettings;
use crate::progress::Progress;
use crate::shading::TranslucentShading;
use glam::DVec3;
use rayon::prelude::*;
use sss_bssrdf::Rgb;
use sss_hierarchy::{IrradianceTree, KdNode, PixelPoint, PixelTree};
use sss_scene::Scene;

/// The options: the irradiance-sample options, ε and ρ.
pub const OPTIONS: [OptionSpec; 5] = [
    SPACING,
    MAX_SAMPLES,
    BOUNCES,
    SOLID_ANGLE,
    OptionSpec {
        name: "rho",
        value_name: "R",
        default: "0.75",
        help: "ρ of Eq. 6: a cluster of pixels is shaded as one when its extent is below \
               ρ / max s_p pixels (0 shades every pixel; the paper uses 0.75)",
        kind: OptionKind::Value,
        values: &[],
    },
];

/// The registry entry.
pub const METHOD: Method = Method {
    name: "dual-tree",
    about: "Milaenen et al. 2019 dual hierarchy (irradiance samples × pixels, Fourier-bandwidth \
            pixel clusters)",
    options: &OPTIONS,
    build: |o| Ok(Box::new(DualTree::from_options(o)?)),
    sweep: Sweep {
        option: "solid-angle",
        label: "solid_angle",
        values: eps_sweep,
    },
    converges_to: Converges::Model,
};

/// The `dual-tree` integrator and its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DualTree {
    /// Irradiance sample placement and lighting.
    pub irradiance: IrradianceSettings,
    /// The solid-angle threshold ε.
    pub eps: f64,
    /// ρ of Eq. 6.
    pub rho: f64,
}

impl Default for DualTree {
    fn default() -> Self {
        DualTree {
            irradiance: IrradianceSettings::default(),
            eps: declared(&OPTIONS, "solid-angle"),
            rho: declared(&OPTIONS, "rho"),
        }
    }
}

impl DualTree {
    /// The settings `options` describe.
    pub fn from_options(o: &MethodOptions) -> Result<Self, Error> {
        let rho: f64 = o.get(&OPTIONS, "rho")?;
        if !(rho.is_finite() && rho >= 0.0) {
            return Err(Error::Input(format!(
                "--rho must be finite and >= 0, got {rho}"
            )));
        }
        Ok(DualTree {
            irradiance: sample_settings(o)?,
            eps: eps_option(o, &OPTIONS, "solid-angle")?,
            rho,
        })
    }
}

/// How SHADE evaluates an illumination node.
#[derive(Clone, Copy)]
enum Source {
    /// As one cluster (flux at its representative position).
    Cluster,
    /// Sample by sample (a leaf reached without passing the solid-angle test).
    Samples,
}

/// Per-task work counters (flushed into [`Counts`] when the task ends).
#[derive(Default)]
struct Local {
    visits: u64,
    clusters: u64,
    samples: u64,
}

struct Dual<'a> {
    px: &'a PixelTree,
    irr: &'a IrradianceTree,
    /// Shading points in the pixel tree's order.
    points: &'a [PixelPoint],
    eps: f64,
    rho: f64,
    sh: &'a TranslucentShading,
}

impl Dual<'_> {
    /// Boxes of pixel node `s` and illumination node `i` are disjoint.
    fn disjoint(&self, s: usize, i: &KdNode<3>) -> bool {
        let c = &self.px.clusters[s];
        (0..3).any(|k| c.world_hi[k] < i.lo[k] || i.hi[k] < c.world_lo[k])
    }

    /// Algorithm 2, DUAL(S, I); `acc` holds S's points.
    fn dual(&self, s: u32, i: u32, acc: &mut [Rgb], l: &mut Local) {
        l.visits += 1;
        let sn = &self.px.tree.nodes[s as usize];
        let inode = &self.irr.tree.nodes[i as usize];
        let cl = &self.irr.clusters[i as usize];
        let d2 = (self.px.clusters[s as usize].position - cl.position).length_squared();
        if accepts(cl.area, d2, self.eps) && self.disjoint(s as usize, inode) {
            self.shade(s, i, Source::Cluster, acc, l);
        } else if sn.is_leaf() && inode.is_leaf() {
            self.shade(s, i, Source::Samples, acc, l);
        } else if sn.is_leaf() {
            self.dual(s, inode.left, acc, l);
            self.dual(s, inode.right, acc, l);
        } else {
            let (a, b) = acc.split_at_mut(self.px.tree.nodes[sn.left as usize].len());
            if inode.is_leaf() {
                self.dual(sn.left, i, a, l);
                self.dual(sn.right, i, b, l);
            } else {
                // Each pixel sees I_L then I_R, as in the paper's order of the four calls.
                self.dual(sn.left, inode.left, a, l);
                self.dual(sn.left, inode.right, a, l);
                self.dual(sn.right, inode.left, b, l);
                self.dual(sn.right, inode.right, b, l);
            }
        }
    }

    /// I's contribution (before the exit weight) at `x`.
    fn contribution(&self, i: u32, src: Source, x: DVec3, l: &mut Local) -> Rgb {
        match src {
            Source::Cluster => {
                let cl = &self.irr.clusters[i as usize];
                l.clusters += 1;
                let rd = self.sh.rd_sample_scene((cl.position - x).length(), cl.area);
                rd_times(rd, cl.flux)
            }
            Source::Samples => {
                let pts = self.irr.points_of(&self.irr.tree.nodes[i as usize]);
                l.samples += pts.len() as u64;
                let mut acc = [0.0; 3];
                add_samples(&mut acc, pts, x, self.sh);
                acc
            }
        }
    }

    /// Algorithm 2, SHADE(S, I) (with the refinement test the right way round).
    fn shade(&self, s: u32, i: u32, src: Source, acc: &mut [Rgb], l: &mut Local) {
        let sn = &self.px.tree.nodes[s as usize];
        let sc = &self.px.clusters[s as usize];
        // LENGTH(S) < P = ρ / max s_p, written without a division (max s_p may be 0).
        if self.px.length_px(sn) * sc.max_rate < self.rho {
            let c = self.contribution(i, src, sc.position, l);
            for a in acc.iter_mut() {
                add_scaled(a, c, 1.0);
            }
        } else if !sn.is_leaf() {
            let (a, b) = acc.split_at_mut(self.px.tree.nodes[sn.left as usize].len());
            self.shade(sn.left, i, src, a, l);
            self.shade(sn.right, i, src, b, l);
        } else {
            let start = sn.start as usize;
            for (k, a) in acc.iter_mut().enumerate() {
                let c = self.contribution(i, src, self.points[start + k].position, l);
                add_scaled(a, c, 1.0);
            }
        }
    }
}

/// The names of the extra layers: s_p per pixel (the largest over its samples, grey) and the
/// pixel clusters (Milaenen et al. Fig. 5: the cut of the pixel tree where LENGTH < ρ / max
/// s_p, one random colour per cluster; a leaf above the cut shows each point alone).
pub const LAYERS: [&str; 2] = ["sampling_rate", "pixel_clusters"];

/// Per point in tree order, a label of the cluster SHADE shades it with (the pixel tree's cut
/// at Eq. 6, independent of the illumination node).
fn cluster_labels(px: &PixelTree, rho: f64) -> Vec<u64> {
    let mut labels = vec![0u64; px.tree.order.len()];
    if px.tree.nodes.is_empty() {
        return labels;
    }
    let mut stack = vec![0u32];
    while let Some(s) = stack.pop() {
        let n = &px.tree.nodes[s as usize];
        let range = n.start as usize..n.end as usize;
        if px.length_px(n) * px.clusters[s as usize].max_rate < rho {
            labels[range].fill(u64::from(s) + 1);
        } else if n.is_leaf() {
            for k in range {
                labels[k] = (1 << 40) + k as u64;
            }
        } else {
            stack.push(n.right);
            stack.push(n.left);
        }
    }
    labels
}

/// A colour in [0.2, 1]³ for a cluster label (0: black).
fn label_colour(label: u64) -> Rgb {
    if label == 0 {
        return [0.0; 3];
    }
    let h = sss_util::splitmix64(label);
    let c = |shift: u32| 0.2 + 0.8 * ((h >> shift) & 0xff) as f64 / 255.0;
    [c(0), c(8), c(16)]
}

impl Integrator for DualTree {
    fn name(&self) -> &'static str {
        METHOD.name
    }

    fn describe(&self) -> String {
        format!(
            "ε = {}, ρ = {}, irradiance sample spacing {} mean free paths, at most {} per object",
            self.eps, self.rho, self.irradiance.spacing_mfp, self.irradiance.max_samples
        )
    }

    fn layer_names(&self) -> &'static [&'static str] {
        &LAYERS
    }

    fn irradiance_settings(&self) -> Option<IrradianceSettings> {
        Some(self.irradiance)
    }

    fn structure_bytes(&self, scene: &Scene, samples: &[(usize, u64, u64)]) -> u64 {
        // At most every camera sample is on a translucent object: its point, its copy in tree
        // order, its sum and index, and the pixel tree over it.
        let cam = &scene.camera;
        let points = u64::from(cam.width)
            .saturating_mul(u64::from(cam.height))
            .saturating_mul(u64::from(cam.pixel_samples.max(1)));
        let n = usize::try_from(points).unwrap_or(usize::MAX / 2);
        let per = 2 * std::mem::size_of::<PixelPoint>() as u64 + 24 + 4;
        illumination_tree_bytes(samples)
            .saturating_add(points.saturating_mul(per))
            .saturating_add(PixelTree::bytes_for(n, PIXEL_LEAF))
    }

    fn integrate(&self, frame: &Frame<'_>, progress: &dyn Progress) -> Result<Shaded, Error> {
        check_radial(frame, METHOD.name)?;
        let LitSamples {
            samples,
            stats: light_stats,
            ..
        } = lit_samples(frame, &self.irradiance)?;
        let trees = frame.timed("illumination_tree", || illumination_trees(frame, &samples));
        let points = frame.timed("fourier", || shading_points(frame))?;
        let pixel_trees = pixel_trees(frame, &points);
        let counts = Counts::default();
        let pixels = frame.gbuffer.pixels();
        let mut rate_layer = vec![[0.0; 3]; pixels];
        let mut cluster_layer = vec![[0.0; 3]; pixels];
        let mut values = vec![[0.0; 3]; frame.gbuffer.samples.len()];
        let shaded_points = frame.timed("shading", || {
            for_each_dual_object(frame, &trees, &pixel_trees, &points, |obj| {
                let (sh, px) = (obj.sh, obj.px);
                let mut acc = vec![[0.0; 3]; obj.ordered.len()];
                if !obj.irr.tree.nodes.is_empty() {
                    let dual = Dual {
                        px,
                        irr: obj.irr,
                        points: &obj.ordered,
                        eps: self.eps,
                        rho: self.rho,
                        sh,
                    };
                    task_slices(px, &mut acc)
                        .into_par_iter()
                        .for_each(|(s, slice)| {
                            progress.advance(slice.len() as u64);
                            let mut l = Local::default();
                            dual.dual(s, 0, slice, &mut l);
                            counts.add(l.visits, l.clusters, l.samples);
                        });
                } else {
                    progress.advance(obj.ordered.len() as u64);
                }
                let labels = cluster_labels(px, self.rho);
                for (k, a) in acc.iter().enumerate() {
                    let gi = obj.sample(k);
                    let g = &frame.gbuffer.samples[gi];
                    let mut v = [0.0; 3];
                    add_weighted(&mut v, *a, sh.exit_weights(g.n, g.wo));
                    values[gi] = v;
                    let p = g.pixel as usize;
                    let r = obj.ordered[k].rate;
                    if r > rate_layer[p][0] {
                        rate_layer[p] = [r; 3];
                    }
                    if g.index == 0 || cluster_layer[p] == [0.0; 3] {
                        cluster_layer[p] = label_colour(labels[k]);
                    }
                }
            })
        });
        // Progress counts every G-buffer sample once: the ones no tree shaded (opaque surfaces,
        // background objects) now.
        progress.advance(frame.gbuffer.samples.len() as u64 - shaded_points);
        let mut stats = counts.stats("node_pairs_visited");
        stats.extend(light_stats);
        let rates: Vec<f64> = points
            .iter()
            .flatten()
            .flat_map(|(p, _)| p.iter().map(|q| q.rate))
            .collect();
        if !rates.is_empty() {
            stats.push(Stat {
                name: "mean_sampling_rate",
                value: rates.iter().sum::<f64>() / rates.len() as f64,
            });
        }
        Ok(Shaded {
            values,
            stats,
            layers: vec![
                Layer {
                    name: LAYERS[0],
                    pixels: rate_layer,
                },
                Layer {
                    name: LAYERS[1],
                    pixels: cluster_layer,
                },
            ],
            ..Shaded::default()
        })
    }
}
