//! A dual-tree traversal with **local expansions** (the fast multipole method's idea,
//! Greengard & Rokhlin 1987, in the dual-tree form of Gray & Moore 2001): the same two trees
//! as [`super::dual_tree`] — a kd-tree over the object's irradiance samples
//! ([`IrradianceTree`]) and one over its shading points in screen space ([`PixelTree`]) — but
//! an accepted pair (S, I) does not shade the pixel cluster S with one constant. It adds the
//! source cluster's R_d, *with its gradient and Hessian*, about S's centre p_S to a local
//! expansion kept per pixel-tree node; once a task's traversal ends the expansions are pushed
//! down the pixel tree and evaluated at every shading point x = p_S + Δx:
//!
//! f(x) ≈ f(p_S) + ∇f · Δx + ½ Δxᵀ H Δx,  f(x) = Φ_I R_d(‖x − p_I‖)
//!
//! (order 2; order 1 stops after the gradient). For a radial R_d(r) with δ = p_S − p_I,
//! r = ‖δ‖, u = δ/r: ∇f = Φ R′ u and H = Φ (R″ uuᵀ + (R′/r)(I − uuᵀ)). R, R′, R″ come from
//! [`sss_bssrdf::Bssrdf::rd_derivatives`] (closed forms for the dipoles and Christensen–Burley,
//! the spline's own derivatives for the tabulated models). The value is the single tree's
//! disk-averaged cluster value ([`TranslucentShading::rd_sample_scene`] with the cluster's area);
//! the derivatives are scaled by the same per-channel factor (the disk average's relative
//! correction varies slowly with r: it is R_d's Laplacian ratio times a²/8).
//!
//! # The error bound behind the acceptance rule
//! The expansion of order p about p_S is exact up to the Taylor remainder: for ‖Δx‖ ≤ r_S (the
//! pixel node's world radius about p_S), |E_p| ≤ r_S^{p+1}/(p+1)! · sup ‖D^{p+1} f‖ over the
//! node, where every point is at least d_n = ‖p_S − p_I‖ − r_S from p_I. The profiles here are
//! sums of terms r^{−k} e^{−σ r} (dipoles, Burley; the tabulated ones are smooth fits of such
//! shapes), whose m-th derivative is bounded by R_d(d_n) · C_m (k/d_n + σ)^m, so the relative
//! error of an accepted pair is
//!
//! |E_p| / f ≲ C ((r_S/d_n) + σ r_S)^{p+1}:
//!
//! order p + 1 in r_S/d_n. The acceptance tests that ratio directly, in solid-angle form, from
//! both sides (symmetric acceptance):
//!
//! - the source seen from the nearest pixel: Δω_I = A_I / d_n² < ε (the single tree's test, at
//!   the nearest pixel rather than at p_S, which bounds the monopole error of the cluster,
//!   O((r_I/d)²) about its irradiance-weighted centre, for every pixel of S);
//! - the pixel node seen from the source: π r_S² / d_n² < ε_px = K ε (K = `--px-ratio`, 4 by
//!   default): this is the (r_S/d_n)^{p+1} of the remainder, O(ε^{(p+1)/2});
//! - d_n > 0 and the world boxes of S and I disjoint, so r → 0 is never expanded about.
//!
//! A pair that passes only one side is not refined blindly; what fails decides what is split,
//! so each kind of interaction of the fast multipole method has its place:
//!
//! - **both** (multipole to local): the cluster's expansion about S, as above;
//! - **the source only** (S too wide for an expansion; multipole to point): S is split, and at
//!   a leaf of S the cluster is evaluated at each of its points, as the single tree would;
//! - **the pixel node only** (the source too wide to be one cluster; particle to local): the
//!   source node is split (while S passes the test below at the source's centre too; else as
//!   for neither), and at a leaf of samples each sample is expanded about S on its
//!   own, if every one of them passes the pixel test at its own distance (a leaf whose box is
//!   disjoint from S's may still hold a sample within S's radius) and in the profile's own
//!   length (below);
//! - **neither**: the wider node (world radius about its centre) is split; at a pair of
//!   leaves each sample that passes the single-sample test on its own is expanded about S, and
//!   the others are summed at every point of S with the same
//!   [`TranslucentShading::add_point_sum`] as `exact` (the samples of one leaf sit at
//!   different distances from S, so the farther ones of a leaf that straddles the near field
//!   still pass).
//!
//! The particle-to-local step is what keeps the cost from growing with the pixel count: the
//! samples near a pixel are no longer summed at every pixel of a leaf but expanded once per
//! pixel node that is small enough, and those nodes shrink in world size as the pixels do.
//! A single sample's expansion carries its disk average's own derivatives
//! ([`TranslucentShading::rd_sample_derivatives_scene`]: the average's correction grows
//! towards the sample, so scaling R_d's derivatives by the average's ratio, as for clusters,
//! errs there; measured on the `--trees` bunny at 2048², ε = 0.05: RMSE 7.6e-4 with the
//! scaling, 8.4e-5 with the derivatives); within three disk radii, where `exact`'s average is
//! a quadrature, those are the quadrature's own central differences, and the distance in the
//! test is taken to the disk's edge (d_n − a), where the average's derivatives are singular.
//! What is left per pixel is the samples whose disk is too close for any pixel node around
//! the pixel to pass (within three disk radii there are about nine at the default spacing):
//! those are summed.
//! Single samples are expanded near the pixels, where the profile's exponential, not the
//! distance, sets how fast it changes; the σ r_S part of the remainder is then bounded by the
//! same test with d_n replaced by min(d_n, 2λ), λ = R_d/|R_d′| the local decay length at the
//! sample's distance (per channel; for R_d ∝ r⁻², 2λ = r, so the test is the geometric one
//! where the profile decays algebraically). Cluster expansions keep the geometric test alone:
//! they are accepted only where A_I/d_n² < ε, far enough that the exponential has already
//! made the pair's share of the pixel small (measured on the `--trees` bunny at 1024², ε =
//! 0.05: the decay-length test on clusters too makes the method 3.8× slower).
//!
//! At ε → 0 nothing is accepted and the method equals `exact` over the same samples to
//! rounding. One parameter ε trades time for error (ε_px follows it).
//!
//! # What the paper's ρ / s_p does here
//! The σ r_S part of the bound is not controlled by the solid angles: a pixel node far from a
//! source may still be wide against the profile's decay length 1/σ. That is what the
//! bandwidth analysis measures: s_p (Milaenen et al. Eq. 4–5) folds the profile's spatial
//! bandwidth B_s into the pixel sampling rate, and ρ / max s_p pixels is the largest cluster
//! over which the shading is band-limited. `--cap-rho ρ` (0, off, by default) keeps that test
//! as a cap on the pixel-node size: an expansion is accepted only when also
//! LENGTH(S) · max s_p < ρ (the paper's Eq. 6); a pair that passes everything but the cap
//! splits S, and at a leaf evaluates the cluster at each of its points (the paper's SHADE
//! below P). The Fourier stage runs only with the cap. Without it, the far-field
//! exponential part of the remainder is left to ε_px: at the distances where a pair is
//! accepted R_d is already small in absolute terms, and the measurements in `docs/compare.md` (and
//! `cargo xtask compare --trees`) show the error falling with ε without a floor.
//!
//! # Work split
//! As in [`super::dual_tree`]: the pixel tree is cut into task subtrees of at most
//! [`TASK_ITEMS`] points (a rule of the tree alone), DUAL(T, root) runs per task in parallel,
//! each task holds the local expansions of its own subtree and pushes them down once at its
//! end, so results do not depend on the thread count. Radial models only.

use super::{
    Counts, ObjectPoints, PIXEL_LEAF, TASK_ITEMS, TreeBalls, accepts, add_samples, ball_outputs,
    eps_sweep, for_each_dual_object, illumination_tree_bytes, illumination_trees, node_balls,
    pair_ball, pixel_point, pixel_trees, rd_times, shading_points, task_slices, tree_balls,
};
use super::{LitSamples, lit_samples};
use crate::Error;
use crate::frame::Frame;
use crate::integrators::Converges;
use crate::integrators::options::{
    BOUNCES, MAX_SAMPLES, SOLID_ANGLE, SPACING, declared, eps_option, sample_settings,
};
use crate::integrators::{
    Integrator, Method, MethodOptions, OptionKind, OptionSpec, Shaded, Stat, Sweep, add_scaled,
    add_weighted, check_radial_balls,
};
use crate::irradiance::IrradianceSettings;
use crate::progress::Progress;
use crate::shading::{DISK_FAR_RATIO, TranslucentShading};
use glam::DVec3;
use rayon::prelude::*;
use sss_bssrdf::Rgb;
use sss_hierarchy::{IrradiancePoint, IrradianceTree, PixelPoint, PixelTree};
use sss_scene::Scene;
use std::f64::consts::PI;
use std::sync::atomic::{AtomicU64, Ordering};

/// The options: the irradiance-sample options, ε, the ratio ε_px / ε, the expansion order and
/// the optional ρ / s_p cap.
pub const OPTIONS: [OptionSpec; 7] = [
    SPACING,
    MAX_SAMPLES,
    BOUNCES,
    SOLID_ANGLE,
    OptionSpec {
        name: "px-ratio",
        value_name: "K",
        default: "4",
        help: "ε_px / ε of the local-expansion dual tree: a pixel node of world radius r takes a \
               source's expansion only when π r² / d² < K ε (d: the source's distance to the \
               node's nearest pixel)",
        kind: OptionKind::Value,
        values: &[],
    },
    OptionSpec {
        name: "expansion-order",
        value_name: "P",
        default: "2",
        help: "Order of the local expansions (1: value and gradient, 2: and the Hessian)",
        kind: OptionKind::Value,
        values: &["1", "2"],
    },
    OptionSpec {
        name: "cap-rho",
        value_name: "R",
        default: "0",
        help: "If > 0, a pixel node takes an expansion only when its screen extent is below \
               ρ / max s_p pixels (Milaenen et al. Eq. 6 as a cap; 0: off, no Fourier stage)",
        kind: OptionKind::Value,
        values: &[],
    },
];

/// The registry entry.
pub const METHOD: Method = Method {
    name: "dual-tree-fmm",
    about: "Dual tree (irradiance samples × pixels) with second-order local expansions per \
            pixel node and symmetric acceptance",
    options: &OPTIONS,
    build: |o| Ok(Box::new(DualTreeFmm::from_options(o)?)),
    sweep: Sweep {
        option: "solid-angle",
        label: "solid_angle",
        values: eps_sweep,
    },
    converges_to: Converges::Model,
};

/// The `dual-tree-fmm` integrator and its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DualTreeFmm {
    /// Irradiance sample placement and lighting.
    pub irradiance: IrradianceSettings,
    /// The solid-angle threshold ε (the source seen from the nearest pixel).
    pub eps: f64,
    /// ε_px / ε (the pixel node seen from the source).
    pub px_ratio: f64,
    /// Expansion order: 1 or 2.
    pub order: u8,
    /// ρ of the optional Eq. 6 cap on the pixel-node size (0: off).
    pub cap_rho: f64,
}

impl Default for DualTreeFmm {
    fn default() -> Self {
        DualTreeFmm {
            irradiance: IrradianceSettings::default(),
            eps: declared(&OPTIONS, "solid-angle"),
            px_ratio: declared(&OPTIONS, "px-ratio"),
            order: declared(&OPTIONS, "expansion-order"),
            cap_rho: declared(&OPTIONS, "cap-rho"),
        }
    }
}

impl DualTreeFmm {
    /// The settings `options` describe.
    pub fn from_options(o: &MethodOptions) -> Result<Self, Error> {
        let px_ratio: f64 = o.get(&OPTIONS, "px-ratio")?;
        if !(px_ratio.is_finite() && px_ratio >= 0.0) {
            return Err(Error::Input(format!(
                "--px-ratio must be finite and >= 0, got {px_ratio}"
            )));
        }
        let order: u8 = o.get(&OPTIONS, "expansion-order")?;
        if !(order == 1 || order == 2) {
            return Err(Error::Input(format!(
                "--expansion-order must be 1 or 2, got {order}"
            )));
        }
        let cap_rho: f64 = o.get(&OPTIONS, "cap-rho")?;
        if !(cap_rho.is_finite() && cap_rho >= 0.0) {
            return Err(Error::Input(format!(
                "--cap-rho must be finite and >= 0, got {cap_rho}"
            )));
        }
        Ok(DualTreeFmm {
            irradiance: sample_settings(o)?,
            eps: eps_option(o, &OPTIONS, "solid-angle")?,
            px_ratio,
            order,
            cap_rho,
        })
    }
}

/// A local expansion about a pixel node's centre, per channel: value, gradient and the
/// symmetric Hessian (xx, xy, xz, yy, yz, zz).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LocalExpansion {
    /// Whether anything was added.
    pub set: bool,
    /// Value at the centre.
    pub value: Rgb,
    /// Gradient per channel.
    pub gradient: [DVec3; 3],
    /// Hessian per channel (xx, xy, xz, yy, yz, zz).
    pub hessian: [[f64; 6]; 3],
}

#[inline]
fn quadratic(h: &[f64; 6], d: DVec3) -> f64 {
    h[0] * d.x * d.x
        + h[3] * d.y * d.y
        + h[5] * d.z * d.z
        + 2.0 * (h[1] * d.x * d.y + h[2] * d.x * d.z + h[4] * d.y * d.z)
}

#[inline]
fn times(h: &[f64; 6], d: DVec3) -> DVec3 {
    DVec3::new(
        h[0] * d.x + h[1] * d.y + h[2] * d.z,
        h[1] * d.x + h[3] * d.y + h[4] * d.z,
        h[2] * d.x + h[4] * d.y + h[5] * d.z,
    )
}

impl LocalExpansion {
    /// Adds the expansion of a radial source about `centre`: per channel, `weight` times the
    /// value `rd[c][0]`, the gradient `rd[c][1]` u and (order 2) the Hessian
    /// `rd[c][2]` uuᵀ + (`rd[c][1]`/r)(I − uuᵀ), with `delta` = centre − source (r = ‖delta‖ > 0).
    pub fn add_radial(&mut self, delta: DVec3, rd: &[[f64; 3]; 3], weight: Rgb, order: u8) {
        let r = delta.length();
        if !(r > 0.0 && r.is_finite()) {
            return;
        }
        let u = delta / r;
        self.set = true;
        for c in 0..3 {
            let w = weight[c];
            let [v, d1, d2] = rd[c];
            self.value[c] += w * v;
            self.gradient[c] += u * (w * d1);
            if order >= 2 {
                let b = w * d1 / r;
                let a = w * d2 - b;
                let h = &mut self.hessian[c];
                h[0] += a * u.x * u.x + b;
                h[1] += a * u.x * u.y;
                h[2] += a * u.x * u.z;
                h[3] += a * u.y * u.y + b;
                h[4] += a * u.y * u.z;
                h[5] += a * u.z * u.z + b;
            }
        }
    }

    /// The expansion at centre + `d` (order 1: value and gradient only).
    #[inline]
    pub fn eval(&self, d: DVec3, order: u8) -> Rgb {
        std::array::from_fn(|c| {
            let mut x = self.value[c] + self.gradient[c].dot(d);
            if order >= 2 {
                x += 0.5 * quadratic(&self.hessian[c], d);
            }
            x
        })
    }

    /// Adds this expansion, re-centred at centre + `d`, to `out` (exact for the polynomial).
    fn shift_into(&self, d: DVec3, order: u8, out: &mut LocalExpansion) {
        out.set = true;
        let v = self.eval(d, order);
        for c in 0..3 {
            out.value[c] += v[c];
            out.gradient[c] += self.gradient[c];
            if order >= 2 {
                out.gradient[c] += times(&self.hessian[c], d);
                for k in 0..6 {
                    out.hessian[c][k] += self.hessian[c][k];
                }
            }
        }
    }
}

/// The largest distance from `p` to a corner of the box [lo, hi].
fn radius_about(p: DVec3, lo: DVec3, hi: DVec3) -> f64 {
    (hi - p).abs().max((p - lo).abs()).length()
}

/// Which of the acceptance tests a pair passes (each includes d_n > 0 and disjoint boxes).
struct PairTests {
    /// The source seen from S's nearest point: A_I / d_n² < ε.
    source: bool,
    /// S seen from the source, π r_S² / d_n² < ε_px, and the ρ cap if it is on.
    pixels: bool,
}

/// One task's state: its pixel subtree's expansions and point sums.
struct Task<'s> {
    root: u32,
    start: usize,
    acc: &'s mut [Rgb],
    local: Vec<LocalExpansion>,
    visits: u64,
    clusters: u64,
    samples: u64,
    /// Samples expanded one by one about a pixel node (particle to local).
    sample_expansions: u64,
}

/// One object's balls as the FMM reads them (`sphere_radius = "local"`).
struct FmmBalls<'a> {
    /// The illumination tree's.
    tree: &'a TreeBalls<'a>,
    /// Per shading point in the pixel tree's order, its radius (mm; NaN: none).
    points: Vec<f64>,
    /// Per pixel-tree node, the radius that stands for its points ([`node_balls`]).
    nodes: Vec<Option<f64>>,
}

struct Fmm<'a> {
    /// Each point's own ball, if the material gives one.
    balls: Option<FmmBalls<'a>>,
    px: &'a PixelTree,
    irr: &'a IrradianceTree,
    /// Shading points in the pixel tree's order.
    points: &'a [PixelPoint],
    sh: &'a TranslucentShading,
    eps: f64,
    eps_px: f64,
    order: u8,
    cap_rho: f64,
    /// World radius of each pixel node about its centre.
    px_radius: Vec<f64>,
    /// World radius of each illumination node about its cluster position.
    irr_radius: Vec<f64>,
}

impl Fmm<'_> {
    /// The ball radius (mm) that stands for illumination node `i`'s samples: NaN with one
    /// profile or where none has one, `None` where the node must be split ([`node_balls`]).
    fn source_ball(&self, i: u32) -> Option<f64> {
        match &self.balls {
            Some(b) => b.tree.nodes[i as usize],
            None => Some(f64::NAN),
        }
    }

    /// [`Self::source_ball`] of pixel node `s`'s shading points.
    fn pixel_ball(&self, s: u32) -> Option<f64> {
        match &self.balls {
            Some(b) => b.nodes[s as usize],
            None => Some(f64::NAN),
        }
    }

    /// The radius (mm) of the `k`-th shading point in the pixel tree's order (NaN: none).
    fn point_ball(&self, k: usize) -> f64 {
        self.balls
            .as_ref()
            .and_then(|b| b.points.get(k).copied())
            .unwrap_or(f64::NAN)
    }

    /// The value of a source of `area` at distance `r` with the pair's ball `pair` (NaN: the
    /// half-space's profile): one irradiance sample's (`single`,
    /// [`TranslucentShading::rd_sample_ball`]) or a cluster's
    /// ([`TranslucentShading::rd_cluster_ball`]).
    fn value(&self, r: f64, area: f64, pair: f64, single: bool) -> Rgb {
        match &self.balls {
            Some(b) if !pair.is_nan() => {
                if single {
                    self.sh.rd_sample_ball(r, area, b.tree.family, pair)
                } else {
                    self.sh.rd_cluster_ball(r, area, b.tree.family, pair)
                }
            }
            _ => self.sh.rd_sample_scene(r, area),
        }
    }

    /// The radius (mm) of the irradiance sample at `j` in the illumination tree's leaf order
    /// (NaN: none).
    fn sample_ball(&self, j: usize) -> f64 {
        self.balls
            .as_ref()
            .and_then(|b| b.tree.samples.get(j).copied())
            .unwrap_or(f64::NAN)
    }

    /// Adds sample `p` (at `j` in the illumination tree's leaf order) at the `k`-th shading
    /// point, as `exact` sums it (with the pair's own ball, if the material gives one).
    fn add_sample_at(&self, acc: &mut Rgb, j: usize, p: &IrradiancePoint, k: usize) {
        let x = self.points[k].position;
        match &self.balls {
            Some(b) => self.sh.add_point_sum_local(
                acc,
                x,
                b.tree.family,
                [(
                    p.position,
                    p.area,
                    p.irradiance,
                    pair_ball(self.point_ball(k), self.sample_ball(j)),
                )],
            ),
            None => add_samples(acc, std::slice::from_ref(p), x, self.sh),
        }
    }

    /// The tests of the module docs for the pair (S, I) at `dn`, the distance from the
    /// source's position to S's nearest point.
    fn tests(&self, s: u32, i: u32, dn: f64) -> PairTests {
        let (su, iu) = (s as usize, i as usize);
        let rs = self.px_radius[su];
        let cl = &self.irr.clusters[iu];
        let dn2 = dn * dn;
        let c = &self.px.clusters[su];
        let n = &self.irr.tree.nodes[iu];
        let apart = dn > 0.0 && (0..3).any(|k| c.world_hi[k] < n.lo[k] || n.hi[k] < c.world_lo[k]);
        PairTests {
            source: apart && accepts(cl.area, dn2, self.eps),
            pixels: apart
                && PI * rs * rs < self.eps_px * dn2
                && (self.cap_rho <= 0.0
                    || self.px.length_px(&self.px.tree.nodes[su]) * c.max_rate < self.cap_rho),
        }
    }

    /// DUAL(S, I) with local expansions.
    fn dual(&self, s: u32, i: u32, t: &mut Task<'_>) {
        t.visits += 1;
        let sn = &self.px.tree.nodes[s as usize];
        let inode = &self.irr.tree.nodes[i as usize];
        let sc = &self.px.clusters[s as usize];
        let cl = &self.irr.clusters[i as usize];
        let rs = self.px_radius[s as usize];
        let delta = sc.position - cl.position;
        let dn = delta.length() - rs;
        let mut ok = self.tests(s, i, dn);
        // With each point's own ball, a node whose radii spread too widely for one to stand
        // for them is split as one too wide is.
        let source_ball = self.source_ball(i);
        let pixel_ball = self.pixel_ball(s);
        ok.source &= source_ball.is_some();
        // Both sides small: the cluster's expansion about S (multipole to local).
        if ok.source
            && ok.pixels
            && let (Some(a), Some(b)) = (source_ball, pixel_ball)
            && let Some(rd) = self.expansion(rs, delta, cl.area, false, pair_ball(a, b))
        {
            self.add_expansion(s, delta, &rd, cl.flux, t);
            t.clusters += 1;
            return;
        }
        // The source small enough for every pixel of S but S too wide for an expansion (or
        // than the ρ cap allows): a leaf evaluates the cluster at each of its points, as the
        // single tree would (multipole to point); an inner node is split.
        if ok.source {
            if sn.is_leaf() {
                let ball = source_ball.unwrap_or(f64::NAN);
                for k in sn.start as usize..sn.end as usize {
                    let x = self.points[k].position;
                    let pair = pair_ball(ball, self.point_ball(k));
                    let rd = self.value((cl.position - x).length(), cl.area, pair, false);
                    add_scaled(&mut t.acc[k - t.start], rd_times(rd, cl.flux), 1.0);
                }
                t.clusters += sn.len() as u64;
            } else {
                self.dual(sn.left, i, t);
                self.dual(sn.right, i, t);
            }
            return;
        }
        // S small enough, seen from the source, but the source too wide to be one cluster: a
        // leaf of samples expands each sample about S (particle to local) if every one of them
        // passes the test; an inner source node is split while S is small in the profile's
        // length there too (tested as for one sample of the node's whole area at its centre,
        // so a node whose disk would reach within three radii of S is refined as for neither).
        if ok.pixels {
            if !inode.is_leaf() {
                let far = delta.length() >= DISK_FAR_RATIO * (cl.area / PI).sqrt();
                if far && self.passing_derivatives(rs, delta, cl.area, true).is_some() {
                    self.dual(s, inode.left, t);
                    self.dual(s, inode.right, t);
                    return;
                }
            } else if self.expand_samples(s, i, rs, t) {
                return;
            }
        }
        match (sn.is_leaf(), inode.is_leaf()) {
            (true, true) => self.leaf_pair(s, i, rs, t),
            (true, false) => {
                self.dual(s, inode.left, t);
                self.dual(s, inode.right, t);
            }
            (false, true) => {
                self.dual(sn.left, i, t);
                self.dual(sn.right, i, t);
            }
            (false, false) => {
                if rs >= self.irr_radius[i as usize] {
                    self.dual(sn.left, i, t);
                    self.dual(sn.right, i, t);
                } else {
                    self.dual(s, inode.left, t);
                    self.dual(s, inode.right, t);
                }
            }
        }
    }

    /// The expansion coefficients (value, first and second radial derivative per channel) of
    /// a source of `area` at `delta` = p_S − p from pixel node S of world radius `rs`, if S
    /// passes the pixel test π r_S² / d² < ε_px with d = d_n = ‖delta‖ − r_S > 0.
    ///
    /// A cluster (`near` false): the disk-averaged value with R_d's derivatives scaled by the
    /// same ratio. A single sample (`near`): the disk average with its own derivatives (none
    /// within 1.25 disk radii), and d = min(d_n − a, 2λ) with a the disk's radius and
    /// λ = R_d/|R_d′| (per channel, at ‖delta‖) the local decay length. For R_d ∝ r⁻² (the
    /// diffusion profiles without their exponential) 2λ = r and the test is the geometric
    /// one; where the exponential dominates, λ → 1/σ and the test bounds the σ r_S part of the
    /// remainder.
    ///
    /// With a pair's ball `pair` (mm; NaN: the material's own profile), or with the material's
    /// one ball ([`TranslucentShading::ball_mm`]), the profile is the ball's
    /// ([`TranslucentShading::rd_sample_ball`]), and its coefficients are those of
    /// the quadratic through its values at ‖delta‖ and ‖delta‖ ± r_S (central differences one
    /// node radius apart: the ball's difference is tabulated, linear between its bins), so the
    /// expansion interpolates the profile over the node's own radial extent; refused where
    /// that extent straddles the ball's diameter, where the profile ends.
    fn expansion(
        &self,
        rs: f64,
        delta: DVec3,
        area: f64,
        near: bool,
        pair: f64,
    ) -> Option<[[f64; 3]; 3]> {
        let mut rd = self.passing_derivatives(rs, delta, area, near)?;
        // A material with one ball has a ball's profile too (tabulated, ending at its
        // diameter): the same interpolation, over its value.
        let pair = if pair.is_nan() {
            self.sh.ball_mm.unwrap_or(f64::NAN)
        } else {
            pair
        };
        if !pair.is_nan() {
            let r = delta.length();
            let h = rs.max(1e-6 * r);
            let end = 2.0 * pair * self.sh.units_per_mm;
            if !(r - h > 0.0) || (r - h < end && end <= r + h) {
                return None;
            }
            let [lo, mid, hi] = [r - h, r, r + h].map(|x| self.value(x, area, pair, near));
            let c = 1.0 / (h * h);
            let d = 0.5 / h;
            return Some(std::array::from_fn(|ch| {
                [
                    mid[ch],
                    (hi[ch] - lo[ch]) * d,
                    (hi[ch] - 2.0 * mid[ch] + lo[ch]) * c,
                ]
            }));
        }
        if near {
            // The value is the disk average's already.
            return Some(rd);
        }
        let disk = self.sh.rd_sample_scene(delta.length(), area);
        for c in 0..3 {
            // The disk average as the value, the point derivatives scaled by its ratio.
            let k = if rd[c][0] > 0.0 {
                disk[c] / rd[c][0]
            } else {
                0.0
            };
            let k = if k.is_finite() { k } else { 0.0 };
            rd[c] = [disk[c], rd[c][1] * k, rd[c][2] * k];
        }
        Some(rd)
    }

    /// The tests of [`Self::expansion`] alone, with the derivatives they were made on (the
    /// value not yet the disk average for a cluster): enough to decide a split.
    fn passing_derivatives(
        &self,
        rs: f64,
        delta: DVec3,
        area: f64,
        near: bool,
    ) -> Option<[[f64; 3]; 3]> {
        let r = delta.length();
        let dn = r - rs;
        let limit = self.eps_px / PI;
        // A single sample's average is singular at its disk's edge: the reach is measured
        // from S to the edge, d_n − a.
        let dn = if near { dn - (area / PI).sqrt() } else { dn };
        // The geometric test first: every reach below is at most d_n, and it costs no
        // evaluation of the profile.
        if !(dn > 0.0 && rs * rs < limit * dn * dn) {
            return None;
        }
        // A single sample near the pixels: its disk average with the average's own
        // derivatives (none where the average is a quadrature: it is summed instead). A
        // cluster, far by A_I/d_n² < ε: R_d's derivatives scaled by the disk's ratio.
        let rd = if near {
            self.sh.rd_sample_derivatives_scene(r, area)?
        } else {
            self.sh.rd_derivatives_scene(r)
        };
        for d in &rd {
            let reach = if near && d[0] > 0.0 && d[1] != 0.0 {
                dn.min(2.0 * d[0] / d[1].abs())
            } else {
                dn
            };
            if !(rs * rs < limit * reach * reach) {
                return None;
            }
        }
        Some(rd)
    }

    /// Expands every sample of source leaf `i` about pixel node `s` if each passes
    /// [`Self::expansion`]; false (and nothing added) otherwise.
    fn expand_samples(&self, s: u32, i: u32, rs: f64, t: &mut Task<'_>) -> bool {
        const MOST: usize = 8;
        let pts = self.irr.points_of(&self.irr.tree.nodes[i as usize]);
        if pts.len() > MOST {
            return false;
        }
        let centre = self.px.clusters[s as usize].position;
        let Some(ball) = self.pixel_ball(s) else {
            return false;
        };
        let first = self.irr.tree.nodes[i as usize].start as usize;
        let mut coefficients = [[[0.0; 3]; 3]; MOST];
        for (j, (p, rd)) in pts.iter().zip(&mut coefficients).enumerate() {
            let pair = pair_ball(ball, self.sample_ball(first + j));
            match self.expansion(rs, centre - p.position, p.area, true, pair) {
                Some(x) => *rd = x,
                None => return false,
            }
        }
        for (p, rd) in pts.iter().zip(&coefficients) {
            self.add_sample_expansion(s, centre - p.position, rd, p, t);
        }
        true
    }

    /// A pair of leaves that the node tests did not accept: each sample that passes
    /// [`Self::expansion`] on its own about S is expanded (particle to local), the others are
    /// summed at every point of S as `exact` sums them. The samples of one leaf sit at
    /// different distances from S, so in a leaf that straddles the near field the farther
    /// samples still pass. The tries cost derivatives; measured together with the near
    /// branch's derivatives (one change, interleaved runs): the `--trees` bunny at 2048²,
    /// ε = 0.05, 18.3–19.5 s against 21.2–24.6 s before, but the dragon at 512², ε = 0.01,
    /// where most tries fail, 19.5–21.6 s against 15.1–16.7 s.
    fn leaf_pair(&self, s: u32, i: u32, rs: f64, t: &mut Task<'_>) {
        let sn = &self.px.tree.nodes[s as usize];
        let pts = self.irr.points_of(&self.irr.tree.nodes[i as usize]);
        let centre = self.px.clusters[s as usize].position;
        // An expansion costs about what a few point evaluations do: not worth trying for a
        // node of fewer points (nor for one whose points do not share one ball).
        let ball = self.pixel_ball(s);
        let try_expansions = sn.len() >= EXPAND_MIN_POINTS && ball.is_some();
        let first = self.irr.tree.nodes[i as usize].start as usize;
        for (j, p) in pts.iter().enumerate() {
            let delta = centre - p.position;
            let pair = pair_ball(ball.unwrap_or(f64::NAN), self.sample_ball(first + j));
            if try_expansions && let Some(rd) = self.expansion(rs, delta, p.area, true, pair) {
                self.add_sample_expansion(s, delta, &rd, p, t);
                continue;
            }
            for k in sn.start as usize..sn.end as usize {
                self.add_sample_at(&mut t.acc[k - t.start], first + j, p, k);
            }
            t.samples += sn.len() as u64;
        }
    }

    /// Adds single sample `p`'s expansion (coefficients from [`Self::expansion`]) about pixel
    /// node `s`'s centre (`delta` = p_S − p), weighted by its flux, and counts it.
    fn add_sample_expansion(
        &self,
        s: u32,
        delta: DVec3,
        rd: &[[f64; 3]; 3],
        p: &IrradiancePoint,
        t: &mut Task<'_>,
    ) {
        let flux = p.irradiance.map(|e| e * p.area);
        self.add_expansion(s, delta, rd, flux, t);
        t.sample_expansions += 1;
    }

    /// Adds a source's expansion (coefficients from [`Self::expansion`]) with weight `flux`
    /// about pixel node `s`'s centre (`delta` = p_S − p).
    fn add_expansion(&self, s: u32, delta: DVec3, rd: &[[f64; 3]; 3], flux: Rgb, t: &mut Task<'_>) {
        let local = &mut t.local[(s - t.root) as usize];
        local.add_radial(delta, rd, flux, self.order);
    }

    /// Pushes the task's expansions down its subtree and evaluates them at its points.
    fn push_down(&self, t: &mut Task<'_>) {
        let root = t.root as usize;
        for n in root..root + t.local.len() {
            let loc = t.local[n - root];
            if !loc.set {
                continue;
            }
            let node = &self.px.tree.nodes[n];
            let centre = self.px.clusters[n].position;
            if node.is_leaf() {
                for k in node.start as usize..node.end as usize {
                    let v = loc.eval(self.points[k].position - centre, self.order);
                    add_scaled(&mut t.acc[k - t.start], v, 1.0);
                }
            } else {
                for ch in [node.left, node.right] {
                    let d = self.px.clusters[ch as usize].position - centre;
                    let mut out = t.local[ch as usize - root];
                    loc.shift_into(d, self.order, &mut out);
                    t.local[ch as usize - root] = out;
                }
            }
        }
    }
}

/// Pixel leaves of fewer points sum a sample at each point instead of trying its expansion.
const EXPAND_MIN_POINTS: usize = 3;

/// The number of nodes in the pre-order subtree of `s` (it spans `s..s + count`).
fn subtree_nodes(px: &PixelTree, s: u32) -> usize {
    let mut last = s;
    loop {
        let n = &px.tree.nodes[last as usize];
        if n.is_leaf() {
            return (last - s) as usize + 1;
        }
        last = n.right;
    }
}

/// The shading points of every visible translucent object without s_p (the cap is off), and
/// the G-buffer index of each, per object.
fn plain_points(frame: &Frame<'_>) -> ObjectPoints {
    let width = frame.gbuffer.width.max(1);
    let mut out: ObjectPoints = (0..frame.scene.objects.len()).map(|_| None).collect();
    for &o in &frame.visible {
        if frame.shading_of(o).is_none() {
            continue;
        }
        let index: Vec<u32> = (0..frame.gbuffer.samples.len() as u32)
            .filter(|&i| frame.gbuffer.samples[i as usize].object == o)
            .collect();
        let points = index
            .iter()
            .map(|&i| pixel_point(&frame.gbuffer.samples[i as usize], width, 0.0))
            .collect();
        out[o as usize] = Some((points, index));
    }
    out
}

impl Integrator for DualTreeFmm {
    fn name(&self) -> &'static str {
        METHOD.name
    }

    fn describe(&self) -> String {
        format!(
            "ε = {}, ε_px = {} ε, order {}, ρ cap {}, irradiance sample spacing {} mean free \
             paths, at most {} per object",
            self.eps,
            self.px_ratio,
            self.order,
            if self.cap_rho > 0.0 {
                self.cap_rho.to_string()
            } else {
                "off".into()
            },
            self.irradiance.spacing_mfp,
            self.irradiance.max_samples
        )
    }

    fn irradiance_settings(&self) -> Option<IrradianceSettings> {
        Some(self.irradiance)
    }

    fn structure_bytes(&self, scene: &Scene, samples: &[(usize, u64, u64)]) -> u64 {
        // As the paper's dual tree (points, sums, the pixel tree), plus a radius per node of
        // both trees and, per thread, one task's expansions.
        let cam = &scene.camera;
        let points = u64::from(cam.width)
            .saturating_mul(u64::from(cam.height))
            .saturating_mul(u64::from(cam.pixel_samples.max(1)));
        let n = usize::try_from(points).unwrap_or(usize::MAX / 2);
        let per = 2 * std::mem::size_of::<PixelPoint>() as u64 + 24 + 4;
        let nodes = 2 * points.div_ceil((PIXEL_LEAF / 2).max(1) as u64);
        let irr_nodes: u64 = samples.iter().fold(0u64, |a, e| a.saturating_add(e.1));
        let task = (2 * TASK_ITEMS as u64) * std::mem::size_of::<LocalExpansion>() as u64;
        illumination_tree_bytes(samples)
            .saturating_add(points.saturating_mul(per))
            .saturating_add(PixelTree::bytes_for(n, PIXEL_LEAF))
            .saturating_add(nodes.saturating_add(irr_nodes).saturating_mul(8))
            .saturating_add(task.saturating_mul(rayon::current_num_threads() as u64))
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
        let points = if self.cap_rho > 0.0 {
            frame.timed("fourier", || shading_points(frame))?
        } else {
            plain_points(frame)
        };
        let pixel_trees = pixel_trees(frame, &points);
        let counts = Counts::default();
        let sample_expansions = AtomicU64::new(0);
        let mut values = vec![[0.0; 3]; frame.gbuffer.samples.len()];
        let shaded_points = frame.timed("shading", || {
            for_each_dual_object(frame, &trees, &pixel_trees, &points, |obj| {
                let (sh, px, irr) = (obj.sh, obj.px, obj.irr);
                let mut acc = vec![[0.0; 3]; obj.ordered.len()];
                if !irr.tree.nodes.is_empty() && !px.tree.nodes.is_empty() {
                    let fmm_balls = tree_balls[obj.object as usize].as_ref().map(|tree| {
                        let points: Vec<f64> = (0..obj.ordered.len())
                            .map(|k| balls.points.get(obj.sample(k)).copied().unwrap_or(f64::NAN))
                            .collect();
                        let nodes = node_balls(&px.tree, &points);
                        FmmBalls {
                            tree,
                            points,
                            nodes,
                        }
                    });
                    let fmm = Fmm {
                        balls: fmm_balls,
                        px,
                        irr,
                        points: &obj.ordered,
                        sh,
                        eps: self.eps,
                        eps_px: self.px_ratio * self.eps,
                        order: self.order,
                        cap_rho: self.cap_rho,
                        px_radius: px
                            .clusters
                            .iter()
                            .map(|c| radius_about(c.position, c.world_lo, c.world_hi))
                            .collect(),
                        irr_radius: irr
                            .tree
                            .nodes
                            .iter()
                            .zip(&irr.clusters)
                            .map(|(n, c)| {
                                radius_about(c.position, DVec3::from(n.lo), DVec3::from(n.hi))
                            })
                            .collect(),
                    };
                    task_slices(px, &mut acc)
                        .into_par_iter()
                        .for_each(|(s, slice)| {
                            progress.advance(slice.len() as u64);
                            let mut t = Task {
                                root: s,
                                start: px.tree.nodes[s as usize].start as usize,
                                acc: slice,
                                local: vec![LocalExpansion::default(); subtree_nodes(px, s)],
                                visits: 0,
                                clusters: 0,
                                samples: 0,
                                sample_expansions: 0,
                            };
                            fmm.dual(s, 0, &mut t);
                            fmm.push_down(&mut t);
                            counts.add(t.visits, t.clusters, t.samples);
                            sample_expansions.fetch_add(t.sample_expansions, Ordering::Relaxed);
                        });
                } else {
                    progress.advance(obj.ordered.len() as u64);
                }
                for (k, a) in acc.iter().enumerate() {
                    let gi = obj.sample(k);
                    let g = &frame.gbuffer.samples[gi];
                    // A truncated expansion may dip below 0 where the sum is near 0.
                    let a = a.map(|v| if v.is_finite() { v.max(0.0) } else { 0.0 });
                    let mut v = [0.0; 3];
                    add_weighted(&mut v, a, sh.exit_weights(g.n, g.wo));
                    values[gi] = v;
                }
            })
        });
        progress.advance(frame.gbuffer.samples.len() as u64 - shaded_points);
        let mut stats = counts.stats("node_pairs_visited");
        stats.extend(light_stats);
        stats.push(Stat {
            name: "sample_expansions",
            value: sample_expansions.load(Ordering::Relaxed) as f64,
        });
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
