//! The fine partition of the surface into cells ("strata") of size about `radius / 5`, on
//! which void filling draws its candidates and the per-sample areas are summed.

use glam::DVec3;

use super::mesh::Mesh;

/// Cell size `h` (radial and tangential extent), as a fraction of the radius.
pub(super) const STRATUM_EDGE: f64 = 0.2;
/// Upper bound on the total number of cells (the cost is about 1 µs each).
const MAX_STRATA: u64 = 1 << 24;

/// Subdivision of the triangles into strata ("cells") of diameter about `h` or less.
///
/// Each triangle is first cut into two right triangles ("halves") at the foot of the
/// altitude onto its longest edge. Each half is then parametrised from its apex (the
/// vertex opposite its shortest edge `Q0 Q1`) as `apex + s (Q(t) - apex)`, with
/// `Q(t) = Q0 + t (Q1 - Q0)` and `(s, t)` in [0, 1]², and cut into a uniform
/// `m_s × m_t` grid in `(s, t)`: `m_s = ⌈longest edge / h⌉`, `m_t = ⌈shortest edge / h⌉`.
/// Cells are trapezoids (triangles in the first row) with exact area
/// `area(half) (s₁² − s₀²) (t₁ − t₀)`. Their radial and tangential extents are at most `h`.
/// So well-shaped triangles get about `2 area / h²` cells, and long skinny triangles get
/// about `length / h` cells, not `(length / h)²`.
///
/// For parallelism and bounded memory, the rows of each half are grouped into work units
/// of at most [`UNIT_CELLS`] cells. Cell ids (for the per-cell random numbers) depend only
/// on the triangle and the cell, not on the grouping.
pub(super) struct Strata {
    pub(super) halves: Vec<Half>,
    pub(super) units: Vec<Unit>,
    pub(super) total: u64,
}

/// A right triangle: half of input triangle `k`, in that triangle's (u, v).
#[derive(Clone, Copy)]
pub(super) struct Half {
    pub(super) k: u32,
    apex: (f64, f64),
    q0: (f64, f64),
    q1: (f64, f64),
    area: f64,
    pub(super) m_s: u32,
    pub(super) m_t: u32,
    /// Id of this half's first cell within its triangle.
    id_base: u64,
}

/// Rows `i0..i1` of half `half`.
#[derive(Clone, Copy)]
pub(super) struct Unit {
    half: u32,
    i0: u32,
    i1: u32,
}

/// One cell of a half.
#[derive(Clone, Copy)]
pub(super) struct StratumCell {
    /// The cell's index within its triangle: the ids of a triangle's cells are
    /// `0..` its cell count, each once.
    pub(super) id: u64,
    pub(super) i: u32,
    pub(super) j: u32,
    pub(super) area: f64,
}

/// Maximum cells per work unit.
const UNIT_CELLS: u64 = 4096;

impl Half {
    /// (u, v) of the point with parameters (s, t), clamped into the triangle against
    /// rounding.
    pub(super) fn uv(&self, s: f64, t: f64) -> (f64, f64) {
        let q = (
            self.q0.0 + t * (self.q1.0 - self.q0.0),
            self.q0.1 + t * (self.q1.1 - self.q0.1),
        );
        let u = self.apex.0 + s * (q.0 - self.apex.0);
        let v = self.apex.1 + s * (q.1 - self.apex.1);
        let (u, v) = (u.clamp(0.0, 1.0), v.clamp(0.0, 1.0));
        if u + v > 1.0 { (u, 1.0 - u) } else { (u, v) }
    }

    /// Uniform point in cell (i, j) from two uniform numbers.
    pub(super) fn sample(&self, i: u32, j: u32, r1: f64, r2: f64) -> (f64, f64) {
        let (ms, mt) = (f64::from(self.m_s), f64::from(self.m_t));
        let (s0, s1) = (f64::from(i) / ms, f64::from(i + 1) / ms);
        // Density proportional to s (the Jacobian) within the row.
        let s = (s0 * s0 + r1 * (s1 * s1 - s0 * s0)).sqrt();
        let t = (f64::from(j) + r2) / mt;
        self.uv(s, t)
    }

    /// Centroid of cell (i, j).
    pub(super) fn centroid(&self, i: u32, j: u32) -> (f64, f64) {
        let i = f64::from(i);
        let s =
            (2.0 / 3.0) * (3.0 * i * i + 3.0 * i + 1.0) / ((2.0 * i + 1.0) * f64::from(self.m_s));
        let t = (f64::from(j) + 0.5) / f64::from(self.m_t);
        self.uv(s, t)
    }
}

impl Strata {
    pub(super) fn new(mesh: &Mesh, r: f64) -> Self {
        let mut h = STRATUM_EDGE * r;
        let mut halves;
        // Keep the number of cells bounded: coarsen h if needed. Every half has at least
        // one cell, so huge meshes get a larger budget.
        let budget = MAX_STRATA.max(2 * mesh.tris.len() as u64);
        let mut tries = 0;
        loop {
            halves = Vec::new();
            let mut total = 0u64;
            for (k, (_, t)) in mesh.tris.iter().enumerate() {
                for half in split_triangle(k as u32, t, mesh.area[k], h) {
                    total = total.saturating_add(u64::from(half.m_s) * u64::from(half.m_t));
                    halves.push(half);
                }
            }
            tries += 1;
            if total <= budget || tries > 64 {
                break;
            }
            h *= (total as f64 / budget as f64).sqrt().max(1.05);
        }
        let mut units = Vec::new();
        let mut total = 0u64;
        for (n, half) in halves.iter().enumerate() {
            let rows = (UNIT_CELLS / u64::from(half.m_t)).max(1) as u32;
            let mut i0 = 0;
            while i0 < half.m_s {
                let i1 = (i0 + rows).min(half.m_s);
                units.push(Unit {
                    half: n as u32,
                    i0,
                    i1,
                });
                i0 = i1;
            }
            total = total.saturating_add(u64::from(half.m_s) * u64::from(half.m_t));
        }
        Strata {
            halves,
            units,
            total,
        }
    }

    /// The cells of a unit, in a fixed order.
    pub(super) fn cells(&self, u: &Unit) -> impl Iterator<Item = (&Half, StratumCell)> + '_ {
        let half = &self.halves[u.half as usize];
        let (ms, mt) = (u64::from(half.m_s), u64::from(half.m_t));
        let row_area = move |i: u32| half.area * (2.0 * f64::from(i) + 1.0) / (ms * ms) as f64;
        (u.i0..u.i1).flat_map(move |i| {
            let a = row_area(i) / mt as f64;
            (0..half.m_t).map(move |j| {
                let cell = StratumCell {
                    id: half.id_base + u64::from(i) * mt + u64::from(j),
                    i,
                    j,
                    area: a,
                };
                (half, cell)
            })
        })
    }
}

/// The two right-triangle halves of triangle `k` (one if the altitude foot is at a vertex).
fn split_triangle(k: u32, t: &[DVec3; 3], area: f64, h: f64) -> Vec<Half> {
    const UV: [(f64, f64); 3] = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)];
    let len = |a: usize, b: usize| (t[a] - t[b]).length();
    // Edge i is opposite vertex i.
    let l = [len(1, 2), len(2, 0), len(0, 1)];
    let mut o = 0;
    for i in 1..3 {
        if l[i] > l[o] {
            o = i;
        }
    }
    let (a, b) = ((o + 1) % 3, (o + 2) % 3);
    let ab = t[b] - t[a];
    let lambda = ((t[o] - t[a]).dot(ab) / ab.length_squared()).clamp(0.0, 1.0);
    let lambda = if lambda.is_finite() { lambda } else { 0.5 };
    let foot3 = t[a] + lambda * ab;
    let foot = (
        UV[a].0 + lambda * (UV[b].0 - UV[a].0),
        UV[a].1 + lambda * (UV[b].1 - UV[a].1),
    );
    let mut out = Vec::with_capacity(2);
    let mut id_base = 0u64;
    // Halves (o, a, foot) and (o, foot, b) with areas proportional to lambda.
    for (p, q, w) in [
        ((t[a], UV[a]), (foot3, foot), lambda),
        ((foot3, foot), (t[b], UV[b]), 1.0 - lambda),
    ] {
        let half_area = area * w;
        // `area > 0` and `w` in [0, 1]: never NaN.
        if half_area <= 0.0 {
            continue;
        }
        let v = [(t[o], UV[o]), p, q];
        let el = |x: usize, y: usize| (v[x].0 - v[y].0).length();
        // Edge i opposite vertex i; the apex is opposite the shortest edge.
        let e = [el(1, 2), el(2, 0), el(0, 1)];
        let mut s = 0;
        for i in 1..3 {
            if e[i] < e[s] {
                s = i;
            }
        }
        let longest = e.iter().copied().fold(0.0, f64::max);
        let cells = |x: f64| {
            let c = (x / h).ceil();
            if c.is_finite() && c >= 1.0 {
                c.min(1e9) as u32
            } else {
                1
            }
        };
        let (m_s, m_t) = (cells(longest), cells(e[s]));
        out.push(Half {
            k,
            apex: v[s].1,
            q0: v[(s + 1) % 3].1,
            q1: v[(s + 2) % 3].1,
            area: half_area,
            m_s,
            m_t,
            id_base,
        });
        id_base += u64::from(m_s) * u64::from(m_t);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_pcg::Pcg64Mcg;

    /// The cells tile each triangle exactly (areas and a Monte Carlo check of the
    /// geometry), respect the size bound, and skinny triangles get O(length / h) cells.
    #[test]
    fn strata_tile_the_triangles() {
        let tris = vec![
            // Equilateral, right, obtuse, and skinny ones (100 x 0.01, flat obtuse).
            [DVec3::ZERO, DVec3::X, DVec3::new(0.5, 0.75f64.sqrt(), 0.0)],
            [DVec3::ZERO, DVec3::X * 2.0, DVec3::Y],
            [DVec3::ZERO, DVec3::X * 3.0, DVec3::new(1.5, 0.2, 0.1)],
            [DVec3::ZERO, DVec3::X * 100.0, DVec3::new(0.0, 0.01, 0.0)],
            [DVec3::ZERO, DVec3::X * 100.0, DVec3::new(50.0, 0.01, 0.0)],
        ];
        let mesh = Mesh::new(&tris);
        let mut rng = Pcg64Mcg::seed_from_u64(1);
        for r in [4.0, 0.4, 0.1] {
            let strata = Strata::new(&mesh, r);
            let h = STRATUM_EDGE * r;
            let n = tris.len();
            let mut counts = vec![0u64; n];
            let mut area = vec![0.0f64; n];
            let mut ids: Vec<Vec<u64>> = vec![Vec::new(); n];
            let mut samples: Vec<Vec<(f64, f64, f64)>> = vec![Vec::new(); n];
            for unit in &strata.units {
                for (half, cell) in strata.cells(unit) {
                    let k = half.k as usize;
                    counts[k] += 1;
                    area[k] += cell.area;
                    ids[k].push(cell.id);
                    // Cell size: radial and tangential extents are at most h, at an angle
                    // of at least 45 degrees, so corners are within 1.85 h.
                    let c = |s: u32, t: u32| {
                        let (u, v) = half.uv(
                            f64::from(s) / f64::from(half.m_s),
                            f64::from(t) / f64::from(half.m_t),
                        );
                        mesh.point(k, u, v)
                    };
                    let (i, j) = (cell.i, cell.j);
                    let corners = [c(i, j), c(i + 1, j), c(i, j + 1), c(i + 1, j + 1)];
                    for a in &corners {
                        for b in &corners {
                            assert!(a.distance(*b) <= 1.85 * h + 1e-12);
                        }
                    }
                    let (u, v) = half.centroid(i, j);
                    assert!(u >= 0.0 && v >= 0.0 && u + v <= 1.0);
                    let (u, v) = half.sample(i, j, rng.random(), rng.random());
                    assert!(u >= 0.0 && v >= 0.0 && u + v <= 1.0);
                    samples[k].push((u, v, cell.area));
                }
            }
            for k in 0..n {
                assert!(
                    (area[k] - mesh.area[k]).abs() < 1e-12 * mesh.area[k],
                    "area {k}"
                );
                ids[k].sort_unstable();
                assert!(
                    ids[k].iter().copied().eq(0..counts[k]),
                    "cell ids of triangle {k} are not 0..{}",
                    counts[k]
                );
            }
            let total: u64 = counts.iter().sum();
            assert_eq!(total, strata.total);
            // Skinny triangles get O(length / h) cells, not O((length / h)²).
            for k in [3, 4] {
                assert!(
                    (counts[k] as f64) < 4.0 * 100.0 / h + 4.0,
                    "{k}: {}",
                    counts[k]
                );
            }
            // Stratified samples weighted by their cell areas are uniform over each
            // triangle: the weighted means of u and v are 1/3.
            // (Only the well-shaped triangles: a skinny one has a single cell across.)
            for (k, sk) in samples.iter().enumerate().take(3) {
                if sk.len() > 1000 {
                    let m = sk.iter().fold((0.0, 0.0, 0.0), |a, b| {
                        (a.0 + b.0 * b.2, a.1 + b.1 * b.2, a.2 + b.2)
                    });
                    let (mu, mv) = (m.0 / m.2, m.1 / m.2);
                    assert!(
                        (mu - 1.0 / 3.0).abs() < 0.01 && (mv - 1.0 / 3.0).abs() < 0.01,
                        "{k}: {mu} {mv}"
                    );
                }
            }
        }
    }
}
