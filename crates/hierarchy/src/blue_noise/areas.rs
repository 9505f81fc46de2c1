//! Phase 3, per-sample areas: a restricted Voronoi diagram approximated on the surface
//! partition. Each stratum gives its exact area to the sample nearest its centroid.

use rayon::prelude::*;

use super::grid::{Grid, NONE};
use super::mesh::Mesh;
use super::strata::Strata;

/// Area of each sample: strata areas given to the sample nearest the stratum centroid.
pub(super) fn assign_areas(mesh: &Mesh, strata: &Strata, grid: &Grid) -> Vec<f64> {
    // Per unit: (sample, area) sums over its strata, in a fixed order.
    let per_unit: Vec<Vec<(u32, f64)>> = strata
        .units
        .par_iter()
        .map(|unit| {
            let mut pts = Vec::new();
            let mut areas = Vec::new();
            for (half, cell) in strata.cells(unit) {
                let (u, v) = half.centroid(cell.i, cell.j);
                let p = mesh.point(half.k as usize, u, v);
                pts.push((grid.cell_of(p), areas.len() as u64, p));
                areas.push(cell.area);
            }
            let mut got = vec![(NONE, 0.0); areas.len()];
            grid.for_each_with_neighbours(&mut pts, &mut Vec::new(), |l, p, nb| {
                got[l as usize] = (grid.nearest_with(p, nb), areas[l as usize]);
            });
            // Merge per sample (stable sort keeps the stratum order within a sample).
            got.sort_by_key(|x| x.0);
            let mut merged: Vec<(u32, f64)> = Vec::new();
            for (s, a) in got {
                match merged.last_mut() {
                    Some(last) if last.0 == s => last.1 += a,
                    _ => merged.push((s, a)),
                }
            }
            merged
        })
        .collect();

    // Neumaier-compensated sums in a fixed order.
    let mut sum = vec![0.0f64; grid.samples.len()];
    let mut comp = vec![0.0f64; grid.samples.len()];
    for &(s, a) in per_unit.iter().flatten() {
        let s = s as usize;
        neumaier_add(&mut sum[s], &mut comp[s], a);
    }
    sum.iter().zip(&comp).map(|(s, c)| s + c).collect()
}

/// Adds `a` to the running sum `sum` whose lost low-order part is `comp` (Neumaier 1974,
/// "Rundungsfehleranalyse einiger Verfahren zur Summation endlicher Summen", ZAMM 54):
/// the compensated total is `sum + comp`.
fn neumaier_add(sum: &mut f64, comp: &mut f64, a: f64) {
    let t = *sum + a;
    if sum.abs() >= a.abs() {
        *comp += (*sum - t) + a;
    } else {
        *comp += (a - t) + *sum;
    }
    *sum = t;
}

#[cfg(test)]
mod tests {
    use super::super::throw;
    use super::*;
    use glam::DVec3;
    use rand::SeedableRng;
    use rand_pcg::Pcg64Mcg;

    /// Sums whose plain f64 total loses everything: each is exact with the compensation.
    #[test]
    fn neumaier_sums_are_exact_where_plain_sums_fail() {
        let total = |xs: &[f64]| {
            let (mut s, mut c) = (0.0, 0.0);
            for &a in xs {
                neumaier_add(&mut s, &mut c, a);
            }
            s + c
        };
        // Neumaier's example (both branches): the plain sum gives 0.
        let xs = [1.0, 1e100, 1.0, -1e100];
        assert_eq!(total(&xs), 2.0);
        assert_eq!(xs.iter().sum::<f64>(), 0.0);
        // Small terms first, then large ones (the ulp of 1e17 is 16): plain gives 0.
        let xs = [1.0, 1.0, 1e17, -1e17];
        assert_eq!(total(&xs), 2.0);
        assert_eq!(xs.iter().sum::<f64>(), 0.0);
        // 1 + 10⁶ × 2⁻⁵³ ones: each is lost against 1 in plain summation.
        let mut xs = vec![1.0];
        xs.extend(std::iter::repeat_n(f64::EPSILON / 2.0, 1_000_000));
        let exact = 1.0 + 1e6 * f64::EPSILON / 2.0;
        assert_eq!(total(&xs), exact);
        assert_eq!(xs.iter().sum::<f64>(), 1.0);
    }

    /// The areas approximate the restricted Voronoi cells: with cells of size r/5 they are
    /// within a few percent (rms) of a 8x finer reference, far below the natural spread of
    /// the cell areas (coefficient of variation ~0.15).
    #[test]
    fn areas_converge_to_the_restricted_voronoi_areas() {
        let mut tris = Vec::new();
        let (nu, nv) = (120, 60);
        let p = |i: usize, j: usize| {
            let th = std::f64::consts::PI * j as f64 / nv as f64;
            let ph = std::f64::consts::TAU * i as f64 / nu as f64;
            DVec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos())
        };
        for j in 0..nv {
            for i in 0..nu {
                tris.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
                tris.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
            }
        }
        let mesh = Mesh::new(&tris);
        let r = 0.1;
        let strata = Strata::new(&mesh, r);
        let mut rng = Pcg64Mcg::seed_from_u64(1);
        let grid = throw(&mesh, &strata, r, usize::MAX, &mut rng, &mut 0).unwrap();
        let reference = assign_areas(&mesh, &Strata::new(&mesh, r / 8.0), &grid);
        let rms = |a: &[f64]| {
            let n = a.len() as f64;
            (a.iter()
                .zip(&reference)
                .map(|(x, y)| ((x - y) / y).powi(2))
                .sum::<f64>()
                / n)
                .sqrt()
        };
        let default = rms(&assign_areas(&mesh, &strata, &grid));
        let coarse = rms(&assign_areas(&mesh, &Strata::new(&mesh, 2.0 * r), &grid));
        // Measured: 0.018 and 0.034.
        assert!(default < 0.025, "rms error {default}");
        assert!(coarse > default, "coarser strata should be less accurate");
    }
}
