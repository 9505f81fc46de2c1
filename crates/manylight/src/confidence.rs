//! Two-sided Student-t quantiles t_α (∫_{−t}^{t} t_ν(x) dx = α; Nabata & Iwasaki §3.3) from
//! `statrs`, tabulated once per confidence level.

use statrs::distribution::{ContinuousCDF, StudentsT};

use crate::Error;

/// Degrees of freedom tabulated exactly with `statrs`; above, the Cornish–Fisher expansion
/// t ≈ z + (z³ + z)/(4ν) + (5z⁵ + 16z³ + 3z)/(96ν²) (Abramowitz & Stegun 26.7.5) is used,
/// whose error at ν > 4096 is below 1e-9 (`statrs` itself loses accuracy above 10⁴ degrees of
/// freedom and never returns for ν = ∞; ../shared/docs/crates.md §2.5).
pub const TABLE_DOF: usize = 4096;

/// t_α for ν = 1, 2, … degrees of freedom.
#[derive(Clone, Debug)]
pub struct StudentT {
    alpha: f64,
    table: Vec<f64>,
    z: f64,
}

impl StudentT {
    /// The table for confidence level `alpha` in (0, 1). Takes a few milliseconds (bisection
    /// in `statrs`): build it once per render.
    pub fn new(alpha: f64) -> Result<StudentT, Error> {
        if !(alpha > 0.0 && alpha < 1.0) {
            return Err(Error::InvalidInput(format!(
                "confidence level α = {alpha} must lie in (0, 1)"
            )));
        }
        let p = 0.5 + 0.5 * alpha;
        let mut table = Vec::with_capacity(TABLE_DOF);
        for nu in 1..=TABLE_DOF {
            let d = StudentsT::new(0.0, 1.0, nu as f64)
                .map_err(|e| Error::InvalidInput(format!("Student t with ν = {nu}: {e}")))?;
            table.push(d.inverse_cdf(p));
        }
        let z = normal_quantile(p);
        Ok(StudentT { alpha, table, z })
    }

    /// The confidence level α.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// t_α for `nu` ≥ 1 degrees of freedom (`nu` = 0 is treated as 1).
    pub fn quantile(&self, nu: usize) -> f64 {
        let nu = nu.max(1);
        if nu <= TABLE_DOF {
            return self.table[nu - 1];
        }
        let (z, n) = (self.z, nu as f64);
        let (z3, z5) = (z * z * z, z * z * z * z * z);
        z + (z3 + z) / (4.0 * n) + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * n * n)
    }
}

/// The standard normal quantile Φ⁻¹(p) by bisection on the normal CDF of `statrs` (the
/// limit of the t table for ν → ∞).
fn normal_quantile(p: f64) -> f64 {
    let n = statrs::distribution::Normal::standard();
    let (mut lo, mut hi) = (-40.0f64, 40.0f64);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if n.cdf(mid) < p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}
