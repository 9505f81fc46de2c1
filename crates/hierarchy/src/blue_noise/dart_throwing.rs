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
