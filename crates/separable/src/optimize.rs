//! A small Nelder–Mead simplex minimiser (Nelder & Mead 1965, with the standard coefficients
//! 1, 2, ½, ½), used by the fitters of [`crate::artist`] and [`crate::gaussians`], whose
//! objectives are cheap, low-dimensional (2 to 6 parameters) and only piecewise smooth (the
//! inner non-negative least-squares solves switch active sets).

/// Result of [`nelder_mead`].
#[derive(Clone, Debug)]
pub(crate) struct Minimum {
    /// Best point found.
    pub x: Vec<f64>,
    /// Objective evaluations used.
    pub evaluations: usize,
    /// Whether the simplex collapsed below the tolerances before `max_evals`.
    pub converged: bool,
}

/// Minimises `f` from the simplex `x0`, `x0 + step·e_i`. Non-finite objective values are
/// treated as +∞. Stops when the spread of objective values is at most
/// `ftol·|f_best| + ftol_abs` and the simplex diameter is at most `xtol`, or after
/// `max_evals` evaluations. The best vertex never gets worse than `f(x0)`.
pub(crate) fn nelder_mead(
    f: &mut dyn FnMut(&[f64]) -> f64,
    x0: &[f64],
    step: f64,
    ftol: f64,
    ftol_abs: f64,
    xtol: f64,
    max_evals: usize,
) -> Minimum {
    let n = x0.len();
    let mut evals = 0usize;
    let mut eval = |x: &[f64], evals: &mut usize| {
        *evals += 1;
        let v = f(x);
        if v.is_finite() { v } else { f64::INFINITY }
    };
    let mut pts: Vec<Vec<f64>> = Vec::with_capacity(n + 1);
    let mut vals: Vec<f64> = Vec::with_capacity(n + 1);
    pts.push(x0.to_vec());
    vals.push(eval(x0, &mut evals));
    for i in 0..n {
        let mut p = x0.to_vec();
        p[i] += step;
        vals.push(eval(&p, &mut evals));
        pts.push(p);
    }
    let mut converged = false;
    while evals < max_evals {
        // Order the vertices by value (stable, so ties keep the earlier, e.g. x0).
        let mut idx: Vec<usize> = (0..=n).collect();
        idx.sort_by(|&a, &b| vals[a].total_cmp(&vals[b]));
        pts = idx.iter().map(|&i| pts[i].clone()).collect();
        vals = idx.iter().map(|&i| vals[i]).collect();
        let (best, worst) = (vals[0], vals[n]);
        let diameter = pts[1..]
            .iter()
            .map(|p| {
                p.iter()
                    .zip(&pts[0])
                    .map(|(a, b)| (a - b).abs())
                    .fold(0.0, f64::max)
            })
            .fold(0.0, f64::max);
        if (worst - best).abs() <= ftol * best.abs() + ftol_abs && diameter <= xtol {
            converged = true;
            break;
        }
        let centroid: Vec<f64> = (0..n)
            .map(|d| pts[..n].iter().map(|p| p[d]).sum::<f64>() / n as f64)
            .collect();
        let along = |t: f64| -> Vec<f64> {
            (0..n)
                .map(|d| centroid[d] + t * (pts[n][d] - centroid[d]))
                .collect()
        };
        let xr = along(-1.0);
        let fr = eval(&xr, &mut evals);
        if fr < vals[0] {
            let xe = along(-2.0);
            let fe = eval(&xe, &mut evals);
            if fe < fr {
                pts[n] = xe;
                vals[n] = fe;
            } else {
                pts[n] = xr;
                vals[n] = fr;
            }
        } else if fr < vals[n - 1] {
            pts[n] = xr;
            vals[n] = fr;
        } else {
            let (xc, fc) = if fr < vals[n] {
                let xc = along(-0.5);
                let fc = eval(&xc, &mut evals);
                (xc, fc)
            } else {
                let xc = along(0.5);
                let fc = eval(&xc, &mut evals);
                (xc, fc)
            };
            if fc < vals[n].min(fr) {
                pts[n] = xc;
                vals[n] = fc;
            } else {
                // Shrink towards the best vertex.
                for i in 1..=n {
                    let p: Vec<f64> = (0..n)
                        .map(|d| pts[0][d] + 0.5 * (pts[i][d] - pts[0][d]))
                        .collect();
                    vals[i] = eval(&p, &mut evals);
                    pts[i] = p;
                }
            }
        }
    }
    let best = (0..=n)
        .min_by(|&a, &b| vals[a].total_cmp(&vals[b]))
        .unwrap_or(0);
    Minimum {
        x: pts[best].clone(),
        evaluations: evals,
        converged,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_rosenbrock_minimum() {
        let mut f = |x: &[f64]| (1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2);
        let m = nelder_mead(&mut f, &[-1.2, 1.0], 0.5, 1e-14, 1e-30, 1e-10, 20_000);
        assert!(m.converged);
        assert!(
            (m.x[0] - 1.0).abs() < 1e-6 && (m.x[1] - 1.0).abs() < 1e-6,
            "{:?}",
            m.x
        );
    }
}
