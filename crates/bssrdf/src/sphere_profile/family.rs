//! Balls of many radii: the sphere profile of a point pair whose radius is its own.
//!
//! [`SphereProfile`](super::SphereProfile) gives one object one radius. A real shape is thin
//! in places (ears, fingers, a dragon's horns) and thick in others, so a renderer that knows
//! a local radius at each surface point (3/4 of the mean cosine-weighted chord into the
//! object: Cauchy's mean chord 4V/A of a convex body, exactly R on a ball of radius R) asks
//! for the profile of a pair of points at the geometric mean of their two radii, which is
//! symmetric in the pair, as reciprocity wants.
//!
//! [`BallFamily`] holds [`SphereDelta`]s at the radii 2^(k/2) mm (integer k) that cover a
//! range, and reads a pair's reshaped profile from the two nodes around its radius, linearly
//! in ln R, each node's difference at the same fraction of its diameter
//! ([`BallFamily::reshape`]): max(0, R_d(r) + Δ(r; R)) for r ≤ 2R, 0 beyond. Each node's walks run [`FAMILY_PHOTONS`] photons
//! per channel (a quarter of one radius's [`PHOTONS`](super::PHOTONS): a family has a dozen
//! nodes or more); a node is computed once per process, medium and radius.

use super::SphereDelta;
use crate::{BssrdfError, EntryDrift, Medium, Rgb};
use std::sync::Arc;

/// Photons per channel and shape of each node's walks.
pub const FAMILY_PHOTONS: u64 = 1 << 15;

/// Nodes per doubling of the radius.
pub const NODES_PER_OCTAVE: f64 = 2.0;

/// Ball deltas at the radii 2^(k/2) mm covering a range, and optionally each ball's drift
/// (see the module documentation).
#[derive(Clone, Debug)]
pub struct BallFamily {
    /// (radius in mm, its difference), by increasing radius; at least one.
    nodes: Vec<(f64, Arc<SphereDelta>)>,
    /// Each node's drift ([`EntryDrift`] in its ball), or empty.
    drifts: Vec<Arc<EntryDrift>>,
}

impl BallFamily {
    /// [`BallFamily::new`] with each node's [`EntryDrift`] too (in its ball, with
    /// [`FAMILY_PHOTONS`] per node and channel), read at the node nearest a pair's radius in
    /// ln R ([`BallFamily::drift`]).
    pub fn with_drift(medium: &Medium, lo: f64, hi: f64) -> Result<BallFamily, BssrdfError> {
        let mut family = Self::new(medium, lo, hi)?;
        family.drifts = family
            .nodes
            .iter()
            .map(|(radius, _)| EntryDrift::cached_with(medium, Some(*radius), FAMILY_PHOTONS))
            .collect::<Result<_, _>>()?;
        Ok(family)
    }

    /// The drift of the node nearest `radius` (mm) in ln R, or `None` when the family has no
    /// drifts or `radius` is not a positive number.
    pub fn drift(&self, radius: f64) -> Option<&EntryDrift> {
        if self.drifts.is_empty() || !(radius > 0.0) || radius.is_nan() {
            return None;
        }
        // The one node read, or of the two the one with the larger weight (the lower on a
        // tie): the nearer in ln R.
        let (reads, n) = self.reads(radius);
        let k = if n == 2 && reads[1].1 > 0.5 {
            reads[1].0
        } else {
            reads[0].0
        };
        self.drifts.get(k).map(Arc::as_ref)
    }

    /// The nodes 2^(k/2) mm from the largest at or below `lo` to the smallest at or above
    /// `hi` (mm, finite, 0 < lo ≤ hi), for `medium`.
    pub fn new(medium: &Medium, lo: f64, hi: f64) -> Result<BallFamily, BssrdfError> {
        if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo <= hi) {
            return Err(BssrdfError::InvalidArgument(format!(
                "ball family: the radii must be finite with 0 < lo <= hi, got {lo} and {hi} mm"
            )));
        }
        let (k0, k1) = (node_index(lo).floor(), node_index(hi).ceil());
        let mut nodes = Vec::new();
        let mut k = k0;
        while k <= k1 {
            let radius = (k / NODES_PER_OCTAVE).exp2();
            nodes.push((
                radius,
                SphereDelta::cached_with(medium, radius, FAMILY_PHOTONS)?,
            ));
            k += 1.0;
        }
        Ok(BallFamily {
            nodes,
            drifts: Vec::new(),
        })
    }

    /// The nodes' radii (mm), increasing.
    pub fn radii(&self) -> Vec<f64> {
        self.nodes.iter().map(|n| n.0).collect()
    }

    /// The profile of channel `ch` at chord `r` (mm) for the ball of radius `radius` (mm),
    /// given the half-space model's value `rd` there (1/mm²): never negative, 0 beyond the
    /// diameter; `rd` itself when `radius` is not a positive number.
    ///
    /// Between the nodes a < R < b each node's difference is scaled to the pair's ball, read at
    /// the same fraction of its own diameter with its density scaled by the ratio of the two
    /// balls' areas: Δ(r; R) = (1 − t) (a/R)² Δ_a(r a/R) + t (b/R)² Δ_b(r b/R), t =
    /// ln(R/a)/ln(b/a). So the light that crosses a ball, which ends at each ball's diameter,
    /// ends at the pair's (read at the same chord instead, a's share would end at 2a, short of
    /// 2R: on a 10 mm ketchup ball, whose red crosses it, that lost 3 % of the red), and each
    /// node's difference keeps its total (∫ Δ 2πr dr), so the total is linear in ln R between
    /// nodes. Near the entry point, where every ball's difference is about 0, the scaling moves
    /// nothing. Radii outside the nodes read the end node as it is (a family covers the radii
    /// its caller asks for; a scaling far outside it would not be bounded).
    pub fn reshape(&self, ch: usize, r: f64, radius: f64, rd: f64) -> f64 {
        self.reshape_rgb(r, radius, [rd; 3])[ch]
    }

    /// [`BallFamily::reshape`] of the three channels at once (the nodes found once).
    pub fn reshape_rgb(&self, r: f64, radius: f64, rd: Rgb) -> Rgb {
        if !(radius > 0.0) || radius.is_nan() {
            return rd;
        }
        let r = r.abs();
        if !(r <= 2.0 * radius) {
            return [0.0; 3];
        }
        let (reads, n) = self.reads(radius);
        std::array::from_fn(|ch| {
            let delta: f64 = reads[..n]
                .iter()
                .map(|&(k, w, s)| w * s * s * self.nodes[k].1.delta(ch, r * s))
                .sum();
            let v = rd[ch] + delta;
            if v.is_finite() { v.max(0.0) } else { 0.0 }
        })
    }

    /// The nodes a ball of `radius` (mm, > 0) reads, as (node, weight, scale): the first `n`
    /// of the pair. Outside the nodes the end node, weight 1, unscaled; between two nodes a
    /// and b each weighted linearly in ln R, scaled by a/R and b/R
    /// ([`BallFamily::reshape`]).
    fn reads(&self, radius: f64) -> ([(usize, f64, f64); 2], usize) {
        let i = self.nodes.partition_point(|n| n.0 <= radius);
        if i == 0 {
            ([(0, 1.0, 1.0); 2], 1)
        } else if i == self.nodes.len() {
            ([(i - 1, 1.0, 1.0); 2], 1)
        } else {
            let (a, b) = (self.nodes[i - 1].0, self.nodes[i].0);
            let t = (radius / a).ln() / (b / a).ln();
            let t = if t.is_finite() {
                t.clamp(0.0, 1.0)
            } else {
                0.0
            };
            ([(i - 1, 1.0 - t, a / radius), (i, t, b / radius)], 2)
        }
    }
}

/// k of the node grid 2^(k/2) at `radius` (mm), as a real number.
fn node_index(radius: f64) -> f64 {
    radius.log2() * NODES_PER_OCTAVE
}

#[cfg(test)]
mod tests {
    use super::*;

    fn skin1() -> Medium {
        Medium::new([0.032, 0.17, 0.48], [0.74, 0.88, 1.01], 0.0, 1.3).unwrap()
    }

    #[test]
    fn nodes_cover_the_range_on_the_half_octave_grid() {
        let f = BallFamily::new(&skin1(), 3.0, 5.0).unwrap();
        let r = f.radii();
        // 2^(3/2) = 2.83 <= 3 and 5 <= 2^(5/2) = 5.66.
        let want = [1.5f64, 2.0, 2.5].map(f64::exp2);
        assert_eq!(r.len(), want.len());
        for (a, b) in r.iter().zip(want) {
            assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        }
        assert!(BallFamily::new(&skin1(), 0.0, 1.0).is_err());
        assert!(BallFamily::new(&skin1(), 2.0, 1.0).is_err());
        assert!(BallFamily::new(&skin1(), 1.0, f64::INFINITY).is_err());
    }

    /// A node's walk (its [`FAMILY_PHOTONS`]) returns the ball's total of the one-radius
    /// profile's walk (four times the photons) within five standard errors of the two
    /// (binomial: each photon escapes or not).
    #[test]
    fn a_nodes_walk_agrees_with_the_one_radius_walk() {
        let m = skin1();
        let f = BallFamily::new(&m, 4.0, 4.0).unwrap();
        let one = SphereDelta::cached(&m, 4.0).unwrap();
        let node = &f.nodes[0].1;
        assert_eq!(node.radius(), 4.0);
        for ch in 0..3 {
            let (a, b) = (node.totals(ch).0, one.totals(ch).0);
            let var = |p: f64, n: u64| p * (1.0 - p) / n as f64;
            let se = (var(a, FAMILY_PHOTONS) + var(b, super::super::PHOTONS)).sqrt();
            assert!(
                (a - b).abs() < 5.0 * se && se < 0.01,
                "channel {ch}: {a} vs {b}, se {se}"
            );
        }
    }

    #[test]
    fn the_drift_is_the_nearest_nodes_in_ln_r() {
        let m = skin1();
        assert!(BallFamily::new(&m, 4.0, 5.0).unwrap().drift(4.0).is_none());
        let f = BallFamily::with_drift(&m, 4.0, 5.0).unwrap();
        let b = 2f64.powf(2.5);
        // ln(4.7/4) = 0.162 < ln(b/4.7) = 0.185; ln(4.8/4) = 0.182 > ln(b/4.8) = 0.164.
        for (radius, want) in [
            (1.0, 4.0),
            (4.0, 4.0),
            (4.7, 4.0),
            (4.8, b),
            (b, b),
            (90.0, b),
        ] {
            let got = f.drift(radius).unwrap().radius().unwrap();
            assert!((got - want).abs() < 1e-12, "{radius}: {got}");
        }
        for bad in [0.0, -1.0, f64::NAN] {
            assert!(f.drift(bad).is_none(), "{bad}");
        }
    }

    #[test]
    fn a_node_radius_reads_its_own_delta_and_between_nodes_lies_between() {
        let m = skin1();
        let f = BallFamily::new(&m, 4.0, 8.0).unwrap();
        let (a, b) = (4.0, 2f64.powf(2.5));
        let da = SphereDelta::cached_with(&m, a, FAMILY_PHOTONS).unwrap();
        let db = SphereDelta::cached_with(&m, b, FAMILY_PHOTONS).unwrap();
        let rd = 0.05;
        let mid = (a * b).sqrt();
        for r in [0.3, 1.0, 3.0, 7.0] {
            // A node's own radius: its own difference at the chord.
            let va = f.reshape(0, r, a, rd);
            assert_eq!(va, (rd + da.delta(0, r)).max(0.0), "r {r}");
            assert_eq!(f.reshape(0, r, b, rd), (rd + db.delta(0, r)).max(0.0));
            // Half way in ln R: the mean of the two, each at the same fraction of its
            // diameter, its density over the ratio of the areas.
            let (sa, sb) = (a / mid, b / mid);
            let want = rd + 0.5 * (sa * sa * da.delta(0, r * sa) + sb * sb * db.delta(0, r * sb));
            let got = f.reshape(0, r, mid, rd);
            assert!(
                (got - want.max(0.0)).abs() <= 1e-12 * (1.0 + want.abs()),
                "r {r}: {got} vs {want}"
            );
        }
        // Beyond the pair's diameter nothing, even where a larger node has light.
        assert_eq!(f.reshape(0, 2.0 * 5.0 + 0.1, 5.0, rd), 0.0);
        // No radius: the half-space's value.
        assert_eq!(f.reshape(0, 1.0, f64::NAN, rd), rd);
        assert_eq!(f.reshape(0, 1.0, 0.0, rd), rd);
        assert_eq!(f.reshape(0, 1.0, -1.0, rd), rd);
        // Outside the range: the end nodes as they are.
        assert_eq!(f.reshape(1, 1.0, 2.0, rd), (rd + da.delta(1, 1.0)).max(0.0));
        assert_eq!(
            f.reshape(1, 10.0, 16.0, rd),
            (rd + f.nodes[2].1.delta(1, 10.0)).max(0.0)
        );
        // Never negative.
        assert_eq!(f.reshape(2, 0.5, 4.0, -1.0), 0.0);
        // The three channels at once are each channel's own.
        for (r, radius) in [
            (0.5, 3.0),
            (2.0, 4.4),
            (6.0, 5.5),
            (9.0, 12.0),
            (1.0, f64::NAN),
        ] {
            let rd = [0.03, 0.05, 0.08];
            let all = f.reshape_rgb(r, radius, rd);
            for c in 0..3 {
                assert_eq!(all[c], f.reshape(c, r, radius, rd[c]), "{r} {radius} {c}");
            }
        }
    }
}
