//! Phase 2, void filling: one uniform candidate per stratum (cell of the surface
//! partition), strata in a seeded random order, which makes the set maximal with respect to
//! that dense stratified candidate set.

use rand::RngExt;
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;
use sss_util::splitmix64;

use super::grid::Grid;
use super::mesh::Mesh;
use super::strata::Strata;
use super::{CapReached, try_add};

/// Void filling of `grid` after dart throwing: one uniform candidate per stratum, strata in
/// random order. [`CapReached`] if more than `cap` samples would be needed.
pub(super) fn fill_voids(
    mesh: &Mesh,
    strata: &Strata,
    grid: &mut Grid,
    cap: usize,
    rng: &mut Pcg64Mcg,
    candidates: &mut usize,
) -> Result<(), CapReached> {
    // Candidates already covered by the phase-1 samples stay covered, so they are
    // filtered out in parallel first; only the survivors are visited, in random order.
    // That is the same process as visiting all of them. The candidate points come from
    // a counter-based hash, so the survivors do not depend on the thread count.
    let stratum_seed = rng.random::<u64>();
    let mut free = uncovered_candidates(mesh, strata, grid, stratum_seed);
    *candidates += strata.total as usize;
    for i in (1..free.len() as u64).rev() {
        let j = rng.random_range(0..=i);
        free.swap(i as usize, j as usize);
    }
    for &(k, u, v) in &free {
        try_add(grid, mesh, cap, k as usize, u, v)?;
    }
    Ok(())
}

/// The void-filling candidates, one per stratum in stratum order, that no sample of `grid`
/// covers, as (index into `mesh.tris`, u, v). Computed in parallel over the work units of
/// `strata`; the result does not depend on the thread count.
fn uncovered_candidates(
    mesh: &Mesh,
    strata: &Strata,
    grid: &Grid,
    stratum_seed: u64,
) -> Vec<(u32, f64, f64)> {
    let per_unit: Vec<Vec<(u32, f64, f64)>> = strata
        .units
        .par_iter()
        .map(|unit| {
            let mut pts = Vec::new();
            let mut uv = Vec::new();
            let mut k = 0;
            for (half, cell) in strata.cells(unit) {
                k = half.k as usize;
                let (r1, r2) = hash_uniforms(stratum_seed ^ splitmix64(half.k.into()), cell.id);
                let (u, v) = half.sample(cell.i, cell.j, r1, r2);
                let p = mesh.point(k, u, v);
                pts.push((grid.cell_of(p), uv.len() as u64, p));
                uv.push((u, v));
            }
            let mut out = Vec::new();
            grid.for_each_with_neighbours(&mut pts, &mut Vec::new(), |l, p, nb| {
                if nb.iter().all(|&(_, q)| q.distance_squared(p) >= grid.r2) {
                    let (u, v) = uv[l as usize];
                    out.push((l, u, v));
                }
            });
            // Back to cell order (the grouping by grid cell reordered them).
            out.sort_unstable_by_key(|x| x.0);
            out.into_iter().map(|(_, u, v)| (k as u32, u, v)).collect()
        })
        .collect();
    per_unit.into_iter().flatten().collect()
}

/// Two uniform numbers in [0, 1) from a counter-based hash ([`splitmix64`]), so that
/// per-stratum candidates do not depend on the order in which threads draw them.
fn hash_uniforms(seed: u64, index: u64) -> (f64, f64) {
    let a = splitmix64(seed ^ splitmix64(index));
    let b = splitmix64(a);
    let to_unit = |x: u64| (x >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    (to_unit(a), to_unit(b))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hash_uniforms_are_uniform_and_distinct() {
        let n = 100_000;
        let (mut s1, mut s2) = (0.0, 0.0);
        for i in 0..n {
            let (a, b) = hash_uniforms(3, i);
            assert!((0.0..1.0).contains(&a) && (0.0..1.0).contains(&b) && a != b);
            s1 += a;
            s2 += b;
        }
        assert!((s1 / n as f64 - 0.5).abs() < 0.005 && (s2 / n as f64 - 0.5).abs() < 0.005);
        assert_ne!(hash_uniforms(3, 7), hash_uniforms(4, 7));
    }
}
