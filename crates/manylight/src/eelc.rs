//! The error estimation for Lightcuts with supersampling and translucency (Sakai, Nabata,
//! Yasuaki & Iwasaki, CVM 2019; "EELC" in Nabata & Iwasaki §5), built on the error-estimation
//! framework of Nabata et al. 2016: stratified sampling of the product graph of a
//! [`GatherTree`] and the shared [`LightTree`], with a Student-t confidence interval, over a
//! FIXED set of N importance-sampled (or uniform) irradiance points per shading point.
//!
//! # The estimate
//!
//! A stratum is a pair (G, L) of a gather cluster and a light cluster, standing for
//! I_(G,L) = Σ_{i∈G} Σ_{j∈L} S_i ⊙ I_j H(y_j, x_i) (gather points of strength
//! S = w(x_o) A_k R_d, [`crate::gather_tree`]; H = G V F_t, `pairs.rs`). It is sampled
//! n_j = 2 times (Nabata & Iwasaki Eq. 5–6 with the gather point in the role of the irradiance
//! and shading points): a gather point i with p = S_i/S_G and a VPL j with p = I_j/I_L by scalar
//! (luminance) weight, and
//!
//! ```text
//! f = S_G I_L · (S_i / S_i,lum) ⊙ (I_j / I_j,lum) · H(y_j, x_i)      (per RGB channel)
//! ```
//!
//! is unbiased for I_(G,L). The pixel estimate sums the strata, s_j² = (f₁ − f₂)²/2 (of the
//! luminances), and ΔI = t_α(ν = J) √(Σ s_j²/2) or t_α √(Σ s_j²) (the two
//! [`Interval`]s of the many-light estimator, which see). Refinement picks the stratum with the
//! largest Popoviciu bound e_j = M_j/(2√2), M_j = S_G I_L H^u(G, L) · chroma(G) (the largest
//! value one luminance sample can take: Σ_c w_c s_c ι_c ≤ max_c s_c when Σ_c w_c ι_c = 1,
//! [`crate::gather_tree::GatherNode::chroma`]), and splits the cluster with the longer box
//! diagonal (Max-Extent, as Sakai et al.), until ΔI < εI.
//!
//! # What differs from the many-light estimator
//!
//! The points are fixed before the pixel is estimated, so a cluster that is one gather point
//! cannot be refined any further: a pair of one gather point and one VPL is evaluated once,
//! exactly (its two samples would agree), and leaves the queue. The interval then measures the
//! error against the **point set's** value, not against the pixel value: the point set's own
//! noise (N draws) is invisible to it, which is why EELC's estimation accuracy falls at small ε
//! (Nabata & Iwasaki Fig. 10). At a fixed stratum count the partition is a function of the
//! bounds alone, so the estimate is unbiased for the point set's value, and therefore for the
//! pixel value over the draws of the points (unbiased importance sampling).
//!
//! # Hazards (as in [`crate::estimator`])
//!
//! The G clamp (same constant in samples and bounds); a pixel whose samples are all 0 after
//! `min_pairs` pairs stops as [`Status::Zero`]; strata with bound 0 are exact zeros, not
//! sampled, not counted in ν; the cap `max_pairs` ([`Status::TripletCap`]); when no stratum is
//! left to refine the value is the exact point-set sum ([`Status::Exact`]).

use std::collections::BinaryHeap;

use crate::Error;
use crate::bounds;
use crate::confidence::StudentT;
use crate::estimator::{
    Interval, Item, PixelEstimate, Rng, SAMPLES_PER_TRIPLET, Status, Visibility,
};
use crate::gather_tree::GatherTree;
use crate::pairs::{Side, refine_side, transfer, transfer_upper};
use crate::profile::{Transmittance, luminance};
use crate::vpl::LightTree;

/// Settings of the EELC estimator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EelcSettings {
    /// Relative error threshold ε (ΔI < εI); 0 refines until a cap or until exact.
    pub epsilon: f64,
    /// The clamp G_max of min(1/d², G_max) (1/length²).
    pub g_max: f64,
    /// Cap on the strata per pixel.
    pub max_pairs: usize,
    /// The stopping tests apply only from this many pairs on (sampled strata and exact pairs
    /// alike; ≥ 1): with few points, single-point pairs (exact) can outnumber the sampled
    /// strata until none is left.
    pub min_pairs: usize,
    /// Which interval to stop on.
    pub interval: Interval,
}

impl EelcSettings {
    /// ε = 2 %, the given G clamp, at most 200 000 strata per pixel (about 22 MB,
    /// [`EelcSettings::peak_pixel_bytes`]), stopping tests from 8 pairs on, the
    /// standard-error interval (as the many-light estimator's defaults).
    pub fn new(g_max: f64) -> EelcSettings {
        EelcSettings {
            epsilon: 0.02,
            g_max,
            max_pairs: 200_000,
            min_pairs: 8,
            interval: Interval::StandardError,
        }
    }

    /// The most memory one pixel's strata can take at the cap (up to 2 · `max_pairs` entries
    /// and their priority queue).
    pub fn peak_pixel_bytes(&self) -> u64 {
        2 * self.max_pairs as u64 * (size_of::<Pair>() + size_of::<Item>()) as u64
    }

    fn validate(&self) -> Result<(), Error> {
        crate::pairs::validate_settings(self.epsilon, self.g_max, self.max_pairs)?;
        let bad = |m: String| Err(Error::InvalidInput(m));
        if self.min_pairs == 0 {
            return bad("min_pairs must be ≥ 1".into());
        }
        Ok(())
    }
}

#[derive(Clone, Copy, Debug)]
struct Pair {
    g: u32,
    l: u32,
    rgb: [f64; 3],
    value: f64,
    s2: f64,
    /// Sampled (bound > 0 and not a single gather point with a single VPL).
    sampled: bool,
    live: bool,
}

#[derive(Default)]
struct Counters {
    evaluations: u64,
    g_clamped: u64,
}

#[derive(Default, Clone, Copy)]
struct Sums {
    rgb: [f64; 3],
    value: f64,
    s2: f64,
    nonzero: usize,
    sampled: usize,
    live: usize,
}

impl Sums {
    fn add(&mut self, p: &Pair, sign: f64) {
        for c in 0..3 {
            self.rgb[c] += sign * p.rgb[c];
        }
        self.value += sign * p.value;
        self.s2 += sign * p.s2;
        let d = |b: bool| usize::from(b);
        if sign > 0.0 {
            self.nonzero += d(p.value > 0.0);
            self.sampled += d(p.sampled);
            self.live += 1;
        } else {
            self.nonzero -= d(p.value > 0.0);
            self.sampled -= d(p.sampled);
            self.live -= 1;
        }
    }
}

fn exact_sums(pairs: &[Pair]) -> Sums {
    let mut s = Sums::default();
    for p in pairs.iter().filter(|p| p.live) {
        s.add(p, 1.0);
    }
    s
}

/// The EELC estimator for the pixels of one translucent object. `Sync`.
#[derive(Debug)]
pub struct EelcEstimator<'a> {
    lights: &'a LightTree,
    ft: &'a Transmittance,
    t: &'a StudentT,
    settings: EelcSettings,
}

impl<'a> EelcEstimator<'a> {
    /// Checks the settings and bundles the shared data.
    pub fn new(
        lights: &'a LightTree,
        ft: &'a Transmittance,
        t: &'a StudentT,
        settings: EelcSettings,
    ) -> Result<EelcEstimator<'a>, Error> {
        settings.validate()?;
        Ok(EelcEstimator {
            lights,
            ft,
            t,
            settings,
        })
    }

    /// The settings.
    pub fn settings(&self) -> &EelcSettings {
        &self.settings
    }

    /// ΔI for J sampled strata and Σ s_j² under the configured interval.
    pub fn delta(&self, strata: usize, sum_s2: f64) -> f64 {
        self.settings
            .interval
            .half_width(self.t, strata, strata, sum_s2)
    }

    /// Estimates one pixel from its gather tree, a visibility test and the pixel's seed
    /// ([`crate::pixel_seed`]). A pure function of its inputs. `triplets` of the result is the
    /// number of strata (pairs), `samples` the (VPL, gather point) evaluations.
    pub fn estimate(
        &self,
        gather: &GatherTree,
        visibility: &dyn Visibility,
        seed: u64,
    ) -> PixelEstimate {
        let mut rng = Rng(sss_util::splitmix64(seed));
        let mut counters = Counters::default();
        let mut pairs: Vec<Pair> = Vec::new();
        let mut heap = BinaryHeap::new();
        let mut sums = Sums::default();
        let push = |p: Pair, e: f64, pairs: &mut Vec<Pair>, heap: &mut BinaryHeap<Item>| {
            if p.sampled {
                heap.push(Item {
                    e,
                    idx: pairs.len() as u32,
                });
            }
            pairs.push(p);
        };
        let (root, e) = self.eval(
            gather.root(),
            self.lights.root(),
            gather,
            visibility,
            &mut rng,
            &mut counters,
        );
        sums.add(&root, 1.0);
        push(root, e, &mut pairs, &mut heap);
        let eps = self.settings.epsilon;
        let status = loop {
            if heap.is_empty() {
                break Status::Exact;
            }
            if sums.live >= self.settings.min_pairs {
                if sums.nonzero == 0 {
                    break Status::Zero;
                }
                if sums.value > 0.0 && self.delta(sums.sampled, sums.s2) < eps * sums.value {
                    sums = exact_sums(&pairs);
                    if self.delta(sums.sampled, sums.s2) < eps * sums.value {
                        break Status::Converged;
                    }
                }
            }
            if sums.live >= self.settings.max_pairs {
                break Status::TripletCap;
            }
            let Some(Item { idx, .. }) = heap.pop() else {
                break Status::Exact;
            };
            let p = pairs[idx as usize];
            let gn = gather.node(p.g);
            let ln = self.lights.node(p.l);
            let children = match refine_side(gn, ln) {
                Some(Side::Gather) => gn.children.map(|[a, b]| [(a, p.l), (b, p.l)]),
                Some(Side::Light) => ln.children.map(|[a, b]| [(p.g, a), (p.g, b)]),
                None => None,
            };
            // Sampled pairs always have a cluster to split (single-point pairs are exact).
            let Some(children) = children else {
                continue;
            };
            sums.add(&p, -1.0);
            pairs[idx as usize].live = false;
            for (g, l) in children {
                let (q, e) = self.eval(g, l, gather, visibility, &mut rng, &mut counters);
                sums.add(&q, 1.0);
                push(q, e, &mut pairs, &mut heap);
            }
        };
        let sums = exact_sums(&pairs);
        let zero_variance = pairs
            .iter()
            .filter(|p| p.live && p.sampled && p.s2 == 0.0)
            .count();
        let delta = self.delta(sums.sampled, sums.s2);
        PixelEstimate {
            rgb: sums.rgb,
            value: sums.value,
            delta,
            std_error: if sums.sampled > 0 {
                delta / self.t.quantile(sums.sampled)
            } else {
                0.0
            },
            triplets: sums.live,
            splits: 0,
            split_cap_hits: 0,
            frozen: 0,
            zero_variance,
            g_clamped: counters.g_clamped,
            samples: counters.evaluations,
            status,
        }
    }

    /// Evaluates a stratum: its samples and its error bound e_j.
    fn eval(
        &self,
        g: u32,
        l: u32,
        gather: &GatherTree,
        visibility: &dyn Visibility,
        rng: &mut Rng,
        counters: &mut Counters,
    ) -> (Pair, f64) {
        let gn = gather.node(g);
        let ln = self.lights.node(l);
        let mut p = Pair {
            g,
            l,
            rgb: [0.0; 3],
            value: 0.0,
            s2: 0.0,
            sampled: false,
            live: true,
        };
        let scale = gn.strength * ln.intensity;
        let m = scale * transfer_upper(gn, ln, self.ft, self.settings.g_max) * gn.chroma;
        if m.is_nan() || m <= 0.0 {
            // Every sample is 0: an exact 0.
            return (p, 0.0);
        }
        let exact = gn.children.is_none() && ln.children.is_none();
        let n = if exact {
            1
        } else {
            SAMPLES_PER_TRIPLET as usize
        };
        let mut f = [0.0f64; 2];
        let mut rgb = [[0.0f64; 3]; 2];
        for k in 0..n {
            let i = gather.sample(g, rng.next_f64());
            let (j, pj) = self.lights.sample(l, rng.next_f64());
            let x = &gather.points()[i as usize];
            let vpl = &self.lights.vpls()[j as usize];
            let (lum_s, lum_i) = (x.scalar(), vpl.scalar_intensity());
            if !(pj > 0.0 && lum_s > 0.0 && lum_i > 0.0) {
                continue;
            }
            counters.evaluations += 1;
            let (h, clamped) = transfer(vpl, x, self.ft, self.settings.g_max, visibility);
            counters.g_clamped += u64::from(clamped);
            if h <= 0.0 {
                continue;
            }
            let w = scale * h / (lum_s * lum_i);
            rgb[k] = std::array::from_fn(|c| w * x.strength[c] * vpl.intensity[c]);
            f[k] = luminance(rgb[k]);
        }
        if exact {
            // One gather point and one VPL: the sample is the pair's value.
            f[1] = f[0];
            rgb[1] = rgb[0];
        }
        p.rgb = std::array::from_fn(|c| 0.5 * (rgb[0][c] + rgb[1][c]));
        p.value = 0.5 * (f[0] + f[1]);
        let diff = f[0] - f[1];
        p.s2 = 0.5 * diff * diff;
        p.sampled = !exact;
        (p, bounds::error_bound(m, SAMPLES_PER_TRIPLET))
    }
}
