//! Multidimensional Lightcuts (Walter, Arbree, Bala & Greenberg, SIGGRAPH 2006) over a fixed
//! set of BSSRDF importance-sampled (or uniform) irradiance points per shading point, the way
//! Bidirectional Lightcuts (Walter, Khungurn & Bala 2012, ref. \[16\] of Nabata & Iwasaki) bring
//! BSSRDF importance sampling into Lightcuts: the MDLC baseline of Nabata & Iwasaki §5.
//!
//! # The cut
//!
//! The product graph pairs a node of the pixel's [`GatherTree`] (gather points: irradiance
//! points carrying w(x_o) A_k R_d, see [`crate::gather_tree`]) with a node of the shared
//! [`LightTree`]. A pair (G, L) stands for Σ_{i∈G} Σ_{j∈L} S_i ⊙ I_j H(y_j, x_i), and MDLC
//! estimates it from the representatives (the cluster-pair approximation of Walter et al.
//! 2006, as in Lightcuts):
//!
//! ```text
//! Î_(G,L) = H(y_rep(L), x_rep(G)) · (Σ_{i∈G} S_i) ⊙ (Σ_{j∈L} I_j)      (per RGB channel)
//! ```
//!
//! with one shadow ray. Its error bound is the pair's upper bound
//! B = H^u(G, L) · LUMINANCE · (Σ S ⊙ Σ I) (H^u of `pairs.rs`: MDLC's cosine bound over
//! the normal cones, the box-to-box distance with the G clamp, F_t at the largest cosine, V ≤ 1):
//! both the true value and the estimate lie in [0, B]. Starting from the root pair, the pair
//! with the largest B is refined (one of its clusters replaced by its two children, the one
//! with the longer box diagonal, as MDLC) until every pair's bound is below ε times the current
//! estimate of the pixel (Lightcuts' Weber-law criterion, Walter et al. 2005; ε = 2 % in
//! both papers). A pair of one gather point and one VPL is evaluated exactly and has bound 0;
//! a pair whose clusters face away from each other has B = 0 and is exactly 0. Children that
//! keep both representatives of their parent reuse its H (as in MDLC: the representative is
//! one of a child's).
//!
//! # What it estimates, and its bias
//!
//! Over the choice of points, Σ over the point set is unbiased for the pixel value of Nabata &
//! Iwasaki Eq. 1 (the same quantity the many-light estimator and `exact` compute); over the
//! choice of representatives (random in proportion to strength for gather clusters, the
//! brighter child's for light clusters) a single pair's estimate is unbiased only for random
//! light representatives, and the cut itself depends on the estimates: **at a finite cut MDLC is
//! biased**, with an error bounded by the sum of its pairs' bounds
//! ([`PixelEstimate::delta`] here), each below ε·Î when it converged. That is no bound on the
//! total error (the paper's point: the cut can hold thousands of pairs), and it says nothing of
//! the point set's own noise.
//!
//! # Caps and hazards
//!
//! A pixel whose estimate stays 0 (all representatives shadowed) never meets the relative
//! criterion: it refines until every pair is exact or the cap `max_pairs` binds
//! ([`Status::TripletCap`]). G is clamped as in the many-light estimator (same constant in the
//! estimate and the bound).

use std::collections::BinaryHeap;

use crate::Error;
use crate::estimator::{Item, PixelEstimate, Status, Visibility};
use crate::gather_tree::GatherTree;
use crate::pairs::{Side, light_rgb_sums, mul3, refine_side, transfer, transfer_upper};
use crate::profile::{Transmittance, luminance};
use crate::vpl::LightTree;

/// Settings of the MDLC cut.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MdlcSettings {
    /// Relative threshold ε of the Weber criterion (every pair's bound < ε·Î); 0 refines until
    /// every pair is exact or the cap binds.
    pub epsilon: f64,
    /// The clamp G_max of min(1/d², G_max) (1/length²), as in the many-light estimator.
    pub g_max: f64,
    /// Cap on the cut size (pairs) per pixel.
    pub max_pairs: usize,
}

impl MdlcSettings {
    /// ε = 2 % (Walter et al. 2005, and Nabata & Iwasaki §5.1), the given G clamp, at most
    /// 200 000 pairs per pixel (about 18 MB, [`MdlcSettings::peak_pixel_bytes`]).
    pub fn new(g_max: f64) -> MdlcSettings {
        MdlcSettings {
            epsilon: 0.02,
            g_max,
            max_pairs: 200_000,
        }
    }

    /// The most memory one pixel's cut can take at the cap: each refinement retires one pair
    /// and adds two, so up to 2 · `max_pairs` entries, and their priority queue.
    pub fn peak_pixel_bytes(&self) -> u64 {
        2 * self.max_pairs as u64 * (size_of::<Pair>() + size_of::<Item>()) as u64
    }

    fn validate(&self) -> Result<(), Error> {
        crate::pairs::validate_settings(self.epsilon, self.g_max, self.max_pairs)
    }
}

/// One pair of the final cut (for inspection and tests).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutPair {
    /// Gather-tree node.
    pub gather: u32,
    /// Light-tree node.
    pub light: u32,
    /// The pair's estimate per RGB channel.
    pub rgb: [f64; 3],
    /// Its error bound (0 for an exact pair).
    pub bound: f64,
}

#[derive(Clone, Copy, Debug)]
struct Pair {
    g: u32,
    l: u32,
    rgb: [f64; 3],
    bound: f64,
    /// H at the representatives (for reuse by children).
    h: f64,
    live: bool,
}

#[derive(Default)]
struct Counters {
    evaluations: u64,
    g_clamped: u64,
}

/// The MDLC cut for the pixels of one translucent object: the light tree (with its per-channel
/// cluster intensities), F_t at the irradiance point and the settings. `Sync`.
#[derive(Debug)]
pub struct MdlcCut<'a> {
    lights: &'a LightTree,
    light_rgb: Vec<[f64; 3]>,
    ft: &'a Transmittance,
    settings: MdlcSettings,
}

impl<'a> MdlcCut<'a> {
    /// Checks the settings and sums the light tree's RGB intensities.
    pub fn new(
        lights: &'a LightTree,
        ft: &'a Transmittance,
        settings: MdlcSettings,
    ) -> Result<MdlcCut<'a>, Error> {
        settings.validate()?;
        Ok(MdlcCut {
            light_rgb: light_rgb_sums(lights.nodes(), lights.vpls()),
            lights,
            ft,
            settings,
        })
    }

    /// The settings.
    pub fn settings(&self) -> &MdlcSettings {
        &self.settings
    }

    /// Cuts one pixel's product graph (deterministic: a function of the trees alone).
    /// `delta` of the result is the sum of the cut's error bounds (see the module doc),
    /// `triplets` the cut size, `samples` the representative evaluations (shadow rays).
    pub fn estimate(&self, gather: &GatherTree, visibility: &dyn Visibility) -> PixelEstimate {
        self.run(gather, visibility, None)
    }

    /// [`MdlcCut::estimate`] and the final cut.
    pub fn estimate_cut(
        &self,
        gather: &GatherTree,
        visibility: &dyn Visibility,
    ) -> (PixelEstimate, Vec<CutPair>) {
        let mut cut = Vec::new();
        let px = self.run(gather, visibility, Some(&mut cut));
        (px, cut)
    }

    fn run(
        &self,
        gather: &GatherTree,
        visibility: &dyn Visibility,
        cut: Option<&mut Vec<CutPair>>,
    ) -> PixelEstimate {
        let mut counters = Counters::default();
        let mut pairs: Vec<Pair> = Vec::new();
        let mut heap = BinaryHeap::new();
        let root = self.eval(
            gather.root(),
            self.lights.root(),
            gather,
            visibility,
            None,
            &mut counters,
        );
        let mut total = root.rgb;
        let mut live = 1usize;
        if root.bound > 0.0 {
            heap.push(Item {
                e: root.bound,
                idx: 0,
            });
        }
        pairs.push(root);
        let eps = self.settings.epsilon;
        let status = loop {
            let Some(&Item { e, idx }) = heap.peek() else {
                break Status::Exact;
            };
            if e < eps * luminance(total) {
                // Confirm on exact sums (the running ones drift by rounding).
                total = exact_total(&pairs);
                if e < eps * luminance(total) {
                    break Status::Converged;
                }
            }
            if live >= self.settings.max_pairs {
                break Status::TripletCap;
            }
            heap.pop();
            let p = pairs[idx as usize];
            let gn = gather.node(p.g);
            let ln = self.lights.node(p.l);
            let children = match refine_side(gn, ln) {
                Some(Side::Gather) => gn.children.map(|[a, b]| [(a, p.l), (b, p.l)]),
                Some(Side::Light) => ln.children.map(|[a, b]| [(p.g, a), (p.g, b)]),
                None => None,
            };
            // Only exact pairs (bound 0) have no children, and they are never queued.
            let Some(children) = children else {
                continue;
            };
            pairs[idx as usize].live = false;
            for (t, v) in total.iter_mut().zip(p.rgb) {
                *t -= v;
            }
            live -= 1;
            for (g, l) in children {
                let same = gather.node(g).representative == gn.representative
                    && self.lights.node(l).representative == ln.representative;
                let q = self.eval(g, l, gather, visibility, same.then_some(p.h), &mut counters);
                for (t, v) in total.iter_mut().zip(q.rgb) {
                    *t += v;
                }
                live += 1;
                if q.bound > 0.0 {
                    heap.push(Item {
                        e: q.bound,
                        idx: pairs.len() as u32,
                    });
                }
                pairs.push(q);
            }
        };
        let rgb = exact_total(&pairs);
        let delta: f64 = pairs.iter().filter(|p| p.live).map(|p| p.bound).sum();
        if let Some(cut) = cut {
            cut.extend(pairs.iter().filter(|p| p.live).map(|p| CutPair {
                gather: p.g,
                light: p.l,
                rgb: p.rgb,
                bound: p.bound,
            }));
        }
        PixelEstimate {
            rgb,
            value: luminance(rgb),
            delta,
            std_error: 0.0,
            triplets: live,
            splits: 0,
            split_cap_hits: 0,
            frozen: 0,
            zero_variance: 0,
            g_clamped: counters.g_clamped,
            samples: counters.evaluations,
            status,
        }
    }

    /// Evaluates the pair (g, l): its bound and its representative estimate (`reuse`: the
    /// parent's H when both representatives are the parent's).
    fn eval(
        &self,
        g: u32,
        l: u32,
        gather: &GatherTree,
        visibility: &dyn Visibility,
        reuse: Option<f64>,
        counters: &mut Counters,
    ) -> Pair {
        let gn = gather.node(g);
        let ln = self.lights.node(l);
        let mut p = Pair {
            g,
            l,
            rgb: [0.0; 3],
            bound: 0.0,
            h: 0.0,
            live: true,
        };
        let strength = mul3(gn.rgb, self.light_rgb[l as usize]);
        let upper = transfer_upper(gn, ln, self.ft, self.settings.g_max) * luminance(strength);
        if upper.is_nan() || upper <= 0.0 {
            // Every (point, VPL) pair faces away: exactly 0.
            return p;
        }
        p.h = match reuse {
            Some(h) => h,
            None => {
                counters.evaluations += 1;
                let vpl = &self.lights.vpls()[ln.representative as usize];
                let x = &gather.points()[gn.representative as usize];
                let (h, clamped) = transfer(vpl, x, self.ft, self.settings.g_max, visibility);
                counters.g_clamped += u64::from(clamped);
                h
            }
        };
        p.rgb = strength.map(|s| s * p.h);
        // One gather point and one VPL: the estimate is the pair's exact value.
        let exact = gn.children.is_none() && ln.children.is_none();
        p.bound = if exact { 0.0 } else { upper };
        p
    }
}

fn exact_total(pairs: &[Pair]) -> [f64; 3] {
    let mut t = [0.0; 3];
    for p in pairs.iter().filter(|p| p.live) {
        for (t, v) in t.iter_mut().zip(p.rgb) {
            *t += v;
        }
    }
    t
}
