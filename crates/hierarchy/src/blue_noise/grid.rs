//! The hash grid of the accepted samples (cell size = radius): the "no sample within the
//! radius" test of both sampling phases, and nearest-sample queries for the areas.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

use glam::DVec3;

/// FxHash-style hasher for grid keys.
#[derive(Default)]
struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }
    fn write_u64(&mut self, x: u64) {
        self.0 = (self.0.rotate_left(5) ^ x).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
    fn write_i64(&mut self, x: i64) {
        self.write_u64(x as u64);
    }
}

pub(super) type Cell = (i64, i64, i64);

#[derive(Clone, Copy)]
pub(super) struct Accepted {
    pub(super) triangle: u32,
    pub(super) u: f64,
    pub(super) v: f64,
    pub(super) position: DVec3,
}

/// Hash grid (cell = radius) with per-cell linked lists of samples.
pub(super) struct Grid {
    origin: DVec3,
    inv_cell: f64,
    cell: f64,
    pub(super) r2: f64,
    head: HashMap<Cell, u32, BuildHasherDefault<CellHasher>>,
    next: Vec<u32>,
    pub(super) samples: Vec<Accepted>,
    /// Bounding box of the occupied cells (for terminating shell searches).
    cmin: [i64; 3],
    cmax: [i64; 3],
}

pub(super) const NONE: u32 = u32::MAX;

impl Grid {
    pub(super) fn new(origin: DVec3, r: f64) -> Self {
        Grid {
            origin,
            // Cells slightly larger than the radius: every sample within the (inflated)
            // radius of a point is then surely in the 27 cells around it.
            inv_cell: 1.0 / (r * (1.0 + 1e-9)),
            cell: r * (1.0 + 1e-9),
            // Slightly inflated so that `|a - b| >= r` also holds when recomputed with
            // `length()` instead of squared distances.
            r2: r * r * (1.0 + 1e-12),
            head: HashMap::default(),
            next: Vec::new(),
            samples: Vec::new(),
            cmin: [i64::MAX; 3],
            cmax: [i64::MIN; 3],
        }
    }

    pub(super) fn cell_of(&self, p: DVec3) -> Cell {
        let q = ((p - self.origin) * self.inv_cell).floor();
        (q.x as i64, q.y as i64, q.z as i64)
    }

    fn cell_samples(&self, c: Cell) -> impl Iterator<Item = u32> + '_ {
        let mut cur = self.head.get(&c).copied().unwrap_or(NONE);
        std::iter::from_fn(move || {
            if cur == NONE {
                None
            } else {
                let out = cur;
                cur = self.next[cur as usize];
                Some(out)
            }
        })
    }

    /// The samples in the 27 cells around `c`, appended to `out` as (index, position).
    fn neighbourhood(&self, c: Cell, out: &mut Vec<(u32, DVec3)>) {
        out.clear();
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let cc = (
                        c.0.wrapping_add(dx),
                        c.1.wrapping_add(dy),
                        c.2.wrapping_add(dz),
                    );
                    out.extend(
                        self.cell_samples(cc)
                            .map(|s| (s, self.samples[s as usize].position)),
                    );
                }
            }
        }
    }

    /// Calls `f(i, p, neighbours)` for each `(i, p)` of `points`, where `neighbours` holds
    /// every sample in the 27 cells around `p`: a superset of the samples within one cell
    /// size of `p`. Points are grouped by cell so that each neighbourhood is gathered once
    /// (much faster than 27 hash lookups per point when many points share a cell).
    pub(super) fn for_each_with_neighbours(
        &self,
        points: &mut [(Cell, u64, DVec3)],
        buf: &mut Vec<(u32, DVec3)>,
        mut f: impl FnMut(u64, DVec3, &[(u32, DVec3)]),
    ) {
        points.sort_unstable_by_key(|&(c, i, _)| (c, i));
        let mut start = 0;
        while start < points.len() {
            let c = points[start].0;
            let end = start + points[start..].partition_point(|q| q.0 == c);
            self.neighbourhood(c, buf);
            for &(_, i, p) in &points[start..end] {
                f(i, p, buf);
            }
            start = end;
        }
    }

    /// Nearest sample to `p` among `neighbours` (ties to the lower index) if it is
    /// provably the nearest overall (within one cell size), else the full search.
    pub(super) fn nearest_with(&self, p: DVec3, neighbours: &[(u32, DVec3)]) -> u32 {
        let mut best = (f64::INFINITY, NONE);
        for &(s, q) in neighbours {
            let d = q.distance_squared(p);
            if d < best.0 || (d == best.0 && s < best.1) {
                best = (d, s);
            }
        }
        if best.1 != NONE && best.0 <= self.cell * self.cell {
            best.1
        } else {
            self.nearest(p)
        }
    }

    /// `true` if no sample is closer than the radius to `p`.
    pub(super) fn is_free(&self, p: DVec3) -> bool {
        let (cx, cy, cz) = self.cell_of(p);
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let c = (
                        cx.wrapping_add(dx),
                        cy.wrapping_add(dy),
                        cz.wrapping_add(dz),
                    );
                    for s in self.cell_samples(c) {
                        if self.samples[s as usize].position.distance_squared(p) < self.r2 {
                            return false;
                        }
                    }
                }
            }
        }
        true
    }

    pub(super) fn insert(&mut self, s: Accepted) {
        let c = self.cell_of(s.position);
        let id = self.samples.len() as u32;
        let prev = self.head.insert(c, id).unwrap_or(NONE);
        self.next.push(prev);
        self.samples.push(s);
        for (a, v) in [c.0, c.1, c.2].into_iter().enumerate() {
            self.cmin[a] = self.cmin[a].min(v);
            self.cmax[a] = self.cmax[a].max(v);
        }
    }

    /// Nearest sample to `p` (ties to the lower index). The grid must not be empty.
    pub(super) fn nearest(&self, p: DVec3) -> u32 {
        let (cx, cy, cz) = self.cell_of(p);
        let c = [cx, cy, cz];
        let mut best = (f64::INFINITY, NONE);
        let consider = |cell: Cell, best: &mut (f64, u32)| {
            for s in self.cell_samples(cell) {
                let d = self.samples[s as usize].position.distance_squared(p);
                if d < best.0 || (d == best.0 && s < best.1) {
                    *best = (d, s);
                }
            }
        };
        // Largest shell that can still contain occupied cells.
        let reach = (0..3)
            .map(|a| {
                c[a].saturating_sub(self.cmin[a])
                    .saturating_abs()
                    .max(self.cmax[a].saturating_sub(c[a]).saturating_abs())
            })
            .max()
            .unwrap_or(0)
            .max(1);
        let mut k: i64 = 0;
        loop {
            // Shell at Chebyshev distance exactly k.
            for dz in -k..=k {
                for dy in -k..=k {
                    let on_face = dz.abs() == k || dy.abs() == k;
                    if on_face {
                        for dx in -k..=k {
                            consider(
                                (
                                    cx.wrapping_add(dx),
                                    cy.wrapping_add(dy),
                                    cz.wrapping_add(dz),
                                ),
                                &mut best,
                            );
                        }
                    } else {
                        consider(
                            (cx.wrapping_sub(k), cy.wrapping_add(dy), cz.wrapping_add(dz)),
                            &mut best,
                        );
                        if k > 0 {
                            consider(
                                (cx.wrapping_add(k), cy.wrapping_add(dy), cz.wrapping_add(dz)),
                                &mut best,
                            );
                        }
                    }
                }
            }
            // All samples within distance k * cell have been seen once shell k is done.
            let covered = k as f64 * self.cell;
            if (best.1 != NONE && best.0 <= covered * covered) || k >= reach {
                return best.1;
            }
            k += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_pcg::Pcg64Mcg;

    #[test]
    fn nearest_matches_brute_force() {
        let mut rng = Pcg64Mcg::seed_from_u64(5);
        let pts: Vec<DVec3> = (0..200)
            .map(|_| DVec3::new(rng.random(), rng.random(), rng.random::<f64>() * 0.1))
            .collect();
        let g = grid_of(&pts, 0.1);
        for _ in 0..500 {
            let p = DVec3::new(rng.random::<f64>() * 3.0 - 1.0, rng.random(), rng.random());
            assert_eq!(g.nearest(p), brute_nearest(&g, p));
        }
    }

    /// A grid of radius `r` holding `points`, sample i at `points[i]`.
    fn grid_of(points: &[DVec3], r: f64) -> Grid {
        let mut g = Grid::new(DVec3::ZERO, r);
        for (i, &p) in points.iter().enumerate() {
            g.insert(Accepted {
                triangle: i as u32,
                u: 0.0,
                v: 0.0,
                position: p,
            });
        }
        g
    }

    /// The brute-force nearest sample, ties to the lower index.
    fn brute_nearest(g: &Grid, p: DVec3) -> u32 {
        let d = |s: u32| g.samples[s as usize].position.distance_squared(p);
        (0..g.samples.len() as u32)
            .min_by(|&a, &b| d(a).total_cmp(&d(b)).then(a.cmp(&b)))
            .expect("a sample")
    }

    /// `nearest_with` (the 27 cells around a point, the full search when their best is
    /// farther than a cell) against brute force, with samples sparse enough (about two
    /// cells apart) that a point's best neighbour is often not provably the nearest.
    #[test]
    fn nearest_with_matches_brute_force_on_sparse_samples() {
        let mut rng = Pcg64Mcg::seed_from_u64(8);
        let pts: Vec<DVec3> = (0..40)
            .map(|_| DVec3::new(rng.random(), rng.random(), rng.random::<f64>() * 0.1))
            .collect();
        let g = grid_of(&pts, 0.1);
        let mut nb = Vec::new();
        let (mut full, mut quick) = (0, 0);
        for _ in 0..4000 {
            let p = DVec3::new(rng.random(), rng.random(), rng.random::<f64>() * 0.1);
            g.neighbourhood(g.cell_of(p), &mut nb);
            let got = g.nearest_with(p, &nb);
            assert_eq!(got, brute_nearest(&g, p), "{p}");
            // Both ways are exercised: some answers come from the neighbours alone.
            let near = nb
                .iter()
                .any(|q| q.1.distance_squared(p) <= g.cell * g.cell);
            if near { quick += 1 } else { full += 1 }
        }
        assert!(quick > 100 && full > 100, "{quick} quick, {full} full");
    }

    /// Exact ties go to the lower index, in both searches, whatever the insertion order.
    #[test]
    fn nearest_ties_go_to_the_lower_index() {
        // p = (0.25, 0.25, 0) is at exactly 0.125 (squared 1/64) from both samples.
        let (a, b) = (DVec3::new(0.25, 0.375, 0.0), DVec3::new(0.25, 0.125, 0.0));
        let p = DVec3::new(0.25, 0.25, 0.0);
        assert_eq!(a.distance_squared(p), b.distance_squared(p));
        for pts in [[a, b], [b, a]] {
            let g = grid_of(&pts, 0.25);
            let mut nb = Vec::new();
            g.neighbourhood(g.cell_of(p), &mut nb);
            assert_eq!(nb.len(), 2);
            assert_eq!(g.nearest(p), 0);
            assert_eq!(g.nearest_with(p, &nb), 0);
            // And in the order the neighbour list happens to have, reversed.
            nb.reverse();
            assert_eq!(g.nearest_with(p, &nb), 0);
        }
    }
}
