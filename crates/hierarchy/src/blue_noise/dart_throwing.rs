//! Phase 1, dart throwing (Cook 1986; Dippé & Wold 1985): candidates drawn uniformly by
//! area, each accepted if no sample lies within the radius, until
//! [`MAX_CONSECUTIVE_FAILURES`] rejections in a row.

use rand::RngExt;
use rand_pcg::Pcg64Mcg;

use super::grid::Grid;
use super::mesh::Mesh;
use super::{CapReached, MAX_CONSECUTIVE_FAILURES, try_add};

/// Dart throwing over the area distribution into `grid`: a triangle by binary search over
/// the cumulative areas, then a uniform point in it. Stops after
/// [`MAX_CONSECUTIVE_FAILURES`] rejections in a row; [`CapReached`] if more than `cap`
/// samples would be needed.
pub(super) fn throw_darts(
    mesh: &Mesh,
    grid: &mut Grid,
    cap: usize,
    rng: &mut Pcg64Mcg,
    candidates: &mut usize,
) -> Result<(), CapReached> {
    let n = mesh.tris.len();
    let mut fails = 0;
    while fails < MAX_CONSECUTIVE_FAILURES {
        *candidates += 1;
        let x = rng.random::<f64>() * mesh.total;
        let k = mesh.cdf.partition_point(|&c| c <= x).min(n - 1);
        let (u, v) = uniform_in(
            &[(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)],
            rng.random(),
            rng.random(),
        );
        if try_add(grid, mesh, cap, k, u, v)? {
            fails = 0;
        } else {
            fails += 1;
        }
    }
    Ok(())
}

/// Uniform point in a triangle given by three (u, v) corners.
fn uniform_in(c: &[(f64, f64); 3], r1: f64, r2: f64) -> (f64, f64) {
    let s = r1.sqrt();
    let (a, b, g) = (1.0 - s, s * (1.0 - r2), s * r2);
    (
        a * c[0].0 + b * c[1].0 + g * c[2].0,
        a * c[0].1 + b * c[1].1 + g * c[2].1,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use rand::SeedableRng;

    /// Dart throwing alone on the unit square at radius r: a Poisson-disk set (no two
    /// samples closer than r) spread evenly, whose count lies between two bounds that do
    /// not depend on the code. Below: the phase stops after 64 rejections in a row, which
    /// while a fifth of the square is still free happens with probability 0.8⁶⁴ ≈ 6·10⁻⁷
    /// per chance, so at the stop more than 80 % of the square lies within r of a sample:
    /// N·πr² ≥ 0.8. Above: random sequential adsorption of disks (the disks of radius r/2
    /// around the samples never overlap) cannot pass the jamming coverage 0.547 (Hinrichsen,
    /// Feder & Jøssang 1986, J. Stat. Phys. 44), here on the square grown by r/2 at each
    /// side, with 5 % for the finite set's spread: N·πr²/4 ≤ 1.05 · 0.547 · (1 + r)².
    #[test]
    fn darts_alone_make_a_poisson_disk_set_between_the_coverage_bounds() {
        let r = 0.02;
        let (a, b, c, d) = (DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y);
        let mesh = Mesh::new(&[[a, b, c], [a, c, d]]);
        let mut grid = Grid::new(mesh.origin, r);
        let mut rng = Pcg64Mcg::seed_from_u64(5);
        let mut candidates = 0;
        assert!(throw_darts(&mesh, &mut grid, usize::MAX, &mut rng, &mut candidates).is_ok());
        let pts: Vec<DVec3> = grid.samples.iter().map(|s| s.position).collect();
        let n = pts.len() as f64;
        let disk = std::f64::consts::PI * r * r;
        let (lo, hi) = (
            0.8 / disk,
            1.05 * 0.547 * (1.0 + r) * (1.0 + r) / (disk / 4.0),
        );
        assert!(n >= lo && n <= hi, "{n} samples, bounds {lo:.0}..{hi:.0}");
        // Each candidate was accepted or rejected, and the phase ended on 64 rejections in a row.
        assert!(candidates >= pts.len() + MAX_CONSECUTIVE_FAILURES);
        for (i, p) in pts.iter().enumerate() {
            assert!((0.0..=1.0).contains(&p.x) && (0.0..=1.0).contains(&p.y) && p.z == 0.0);
            for q in &pts[..i] {
                assert!(p.distance(*q) >= r, "{p} and {q} closer than {r}");
            }
        }
        // Evenly by area: each half of the square (and each triangle) holds half of them,
        // within 5 standard deviations of a binomial count.
        let half = |f: &dyn Fn(&DVec3) -> bool| pts.iter().filter(|p| f(p)).count() as f64;
        let tol = 5.0 * (0.25 * n).sqrt();
        for side in [
            half(&|p| p.x < 0.5),
            half(&|p| p.y < 0.5),
            half(&|p| p.y < p.x),
        ] {
            assert!((side - n / 2.0).abs() <= tol, "{side} of {n}");
        }
    }
}
