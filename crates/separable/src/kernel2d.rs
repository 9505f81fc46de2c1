//! The discretised 2D diffuse reflectance kernel R_d(x, y) = R_d(√(x² + y²)) (Jimenez et al.
//! 2015, §3, Eq. 1): the matrix every other kernel of this crate is derived from or compared
//! with.
//!
//! The kernel lives on an N × N grid (N odd) of square cells of side h centred on the origin,
//! covering [−W, W]² where W is the radius holding a chosen fraction of every channel's
//! energy ([`Bssrdf::radius_for_energy`], largest over channels). Each entry is the cell's
//! *mass* ∫∫_cell R_d dx dy, integrated with an m × m Gauss–Legendre rule (no sample sits on
//! the r = 0 peak). The masses are then scaled per channel to the requested [`Energy`]
//! (the model's total diffuse reflectance by default), which compensates the energy outside
//! the grid; [`Kernel2d::captured_fraction`] records how much the grid held before.

use crate::Rgb;
use crate::error::{SeparableError, ensure};
use crate::kernel::Energy;
use sss_bssrdf::Bssrdf;
use sss_bssrdf::quadrature::gauss_legendre;

/// Largest accepted cells per side of a 2D kernel grid: 4095² cells × 3 channels × 8 bytes
/// ≈ 384 MiB. The grid is N² f64 per channel, so an absurd N (10⁸) is refused with an error
/// naming N and the bytes instead of an allocation failure.
pub const MAX_CELLS: usize = 4095;

/// Bytes of the cell masses of an N × N grid (3 channels of f64; saturating).
pub fn grid_bytes(cells: usize) -> u64 {
    (cells as u64)
        .saturating_mul(cells as u64)
        .saturating_mul(3 * std::mem::size_of::<f64>() as u64)
}

fn check_cells(cells: usize) -> Result<(), SeparableError> {
    ensure(cells <= MAX_CELLS, || {
        format!(
            "cells = {cells} would need {} bytes for the {cells}² grid, over the limit of \
             {MAX_CELLS} cells per side ({} bytes)",
            grid_bytes(cells),
            grid_bytes(MAX_CELLS)
        )
    })
}

/// How to discretise a model's kernel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kernel2dSpec {
    /// Cells per side, odd (default 127).
    pub cells: usize,
    /// Fraction of each channel's energy the grid's inscribed disk must hold, in (0, 1)
    /// (default 0.99).
    pub energy_fraction: f64,
    /// Gauss–Legendre points per cell and axis (default 4).
    pub subsamples: usize,
    /// What the masses sum to after scaling (default the total diffuse reflectance).
    pub energy: Energy,
}

impl Default for Kernel2dSpec {
    fn default() -> Self {
        Kernel2dSpec {
            cells: 127,
            energy_fraction: 0.99,
            subsamples: 4,
            energy: Energy::TotalReflectance,
        }
    }
}

/// A discretised 2D kernel: cell masses per channel on an N × N grid centred on 0.
#[derive(Clone, Debug, PartialEq)]
pub struct Kernel2d {
    /// Cells per side (odd).
    pub cells: usize,
    /// Cell side h (mm).
    pub cell_mm: f64,
    /// Cell masses per channel, row-major: `mass[c][iy * cells + ix]` for the cell centred
    /// at (x, y) = (`offset_mm(ix)`, `offset_mm(iy)`) ([`Kernel2d::offset_mm`]). Dimensionless.
    pub mass: [Vec<f64>; 3],
    /// Σ mass per channel (the kernel's energy after scaling).
    pub total: Rgb,
    /// Before scaling, the grid's energy as a fraction of the model's total diffuse
    /// reflectance (1 for kernels built from a density with [`Kernel2d::from_density`]).
    pub captured_fraction: Rgb,
}

impl Kernel2d {
    /// Discretises `model`'s R_d on the grid of `spec`.
    pub fn from_model(model: &dyn Bssrdf, spec: &Kernel2dSpec) -> Result<Self, SeparableError> {
        ensure(spec.cells % 2 == 1 && spec.cells >= 3, || {
            format!("cells = {} must be odd and at least 3", spec.cells)
        })?;
        check_cells(spec.cells)?;
        ensure(
            spec.energy_fraction > 0.0 && spec.energy_fraction < 1.0,
            || {
                format!(
                    "energy_fraction = {} must be in (0, 1)",
                    spec.energy_fraction
                )
            },
        )?;
        ensure((1..=64).contains(&spec.subsamples), || {
            format!("subsamples = {} must be in 1..=64", spec.subsamples)
        })?;
        let radius = (0..3)
            .map(|c| model.radius_for_energy(c, spec.energy_fraction))
            .fold(0.0, f64::max);
        ensure(radius > 0.0 && radius.is_finite(), || {
            format!("the model's energy radius {radius} is not positive and finite")
        })?;
        let n = spec.cells;
        let h = 2.0 * radius / n as f64;
        let half = n / 2;
        let (gx, gw) = gauss_legendre(spec.subsamples);
        let mut mass: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; n * n]);
        // R_d is radial: integrate one octant (half ≤ ix ≤ iy) and mirror it.
        for iy in half..n {
            for ix in half..=iy {
                let (cx, cy) = ((ix - half) as f64 * h, (iy - half) as f64 * h);
                let mut m = [0.0; 3];
                for (xa, wa) in gx.iter().zip(gw) {
                    for (xb, wb) in gx.iter().zip(gw) {
                        let (x, y) = (cx + 0.5 * h * xa, cy + 0.5 * h * xb);
                        let r = (x * x + y * y).sqrt();
                        let w = wa * wb * 0.25 * h * h;
                        for (c, mc) in m.iter_mut().enumerate() {
                            let v = model.rd(c, r);
                            if v.is_finite() {
                                *mc += w * v;
                            }
                        }
                    }
                }
                let (dx, dy) = (ix - half, iy - half);
                for (a, b) in [(dx, dy), (dy, dx)] {
                    for (sx, sy) in [(1i64, 1i64), (-1, 1), (1, -1), (-1, -1)] {
                        let px = (half as i64 + sx * a as i64) as usize;
                        let py = (half as i64 + sy * b as i64) as usize;
                        for c in 0..3 {
                            mass[c][py * n + px] = m[c].max(0.0);
                        }
                    }
                }
            }
        }
        let mut kernel = Kernel2d {
            cells: n,
            cell_mm: h,
            total: [0.0; 3],
            captured_fraction: [0.0; 3],
            mass,
        };
        let raw = kernel.sum();
        let mut target = [0.0; 3];
        for c in 0..3 {
            let model_total = model.total_diffuse_reflectance(c);
            let model_total = if model_total.is_finite() {
                model_total.max(0.0)
            } else {
                0.0
            };
            kernel.captured_fraction[c] = if model_total > 0.0 {
                raw[c] / model_total
            } else {
                0.0
            };
            target[c] = match spec.energy {
                Energy::TotalReflectance => model_total,
                Energy::Unit => 1.0,
            };
        }
        kernel.scale_to(target)?;
        Ok(kernel)
    }

    /// A kernel from an arbitrary density (1/mm², per channel) on `cells` (odd) cells of side
    /// `cell_mm`, integrated with `subsamples`² Gauss–Legendre points per cell, not rescaled.
    pub fn from_density(
        cells: usize,
        cell_mm: f64,
        subsamples: usize,
        density: impl Fn(f64, f64) -> Rgb,
    ) -> Result<Self, SeparableError> {
        ensure(cells % 2 == 1, || format!("cells = {cells} must be odd"))?;
        check_cells(cells)?;
        ensure(cell_mm > 0.0 && cell_mm.is_finite(), || {
            format!("cell_mm = {cell_mm} must be positive and finite")
        })?;
        ensure((1..=64).contains(&subsamples), || {
            format!("subsamples = {subsamples} must be in 1..=64")
        })?;
        let (gx, gw) = gauss_legendre(subsamples);
        let half = (cells / 2) as f64;
        let h = cell_mm;
        let mut mass: [Vec<f64>; 3] = std::array::from_fn(|_| vec![0.0; cells * cells]);
        for iy in 0..cells {
            for ix in 0..cells {
                let (cx, cy) = ((ix as f64 - half) * h, (iy as f64 - half) * h);
                let mut m = [0.0; 3];
                for (xa, wa) in gx.iter().zip(gw) {
                    for (xb, wb) in gx.iter().zip(gw) {
                        let d = density(cx + 0.5 * h * xa, cy + 0.5 * h * xb);
                        for c in 0..3 {
                            if d[c].is_finite() {
                                m[c] += wa * wb * 0.25 * h * h * d[c];
                            }
                        }
                    }
                }
                for c in 0..3 {
                    mass[c][iy * cells + ix] = m[c];
                }
            }
        }
        let mut k = Kernel2d {
            cells,
            cell_mm,
            mass,
            total: [0.0; 3],
            captured_fraction: [1.0; 3],
        };
        k.total = k.sum();
        Ok(k)
    }

    fn sum(&self) -> Rgb {
        std::array::from_fn(|c| self.mass[c].iter().sum())
    }

    fn scale_to(&mut self, target: Rgb) -> Result<(), SeparableError> {
        let raw = self.sum();
        for c in 0..3 {
            if target[c] == 0.0 {
                self.mass[c].iter_mut().for_each(|m| *m = 0.0);
                self.total[c] = 0.0;
                continue;
            }
            if !(raw[c] > 0.0) {
                return Err(SeparableError::ZeroEnergy { channel: c });
            }
            let s = target[c] / raw[c];
            self.mass[c].iter_mut().for_each(|m| *m *= s);
            self.total[c] = self.mass[c].iter().sum();
        }
        Ok(())
    }

    /// The same kernel scaled so each channel sums to `target`.
    pub fn with_energy(&self, target: Rgb) -> Result<Self, SeparableError> {
        ensure(target.iter().all(|t| *t >= 0.0 && t.is_finite()), || {
            format!("target {target:?} must be finite and non-negative")
        })?;
        let mut k = self.clone();
        k.scale_to(target)?;
        Ok(k)
    }

    /// Half-width W of the grid (mm): cells·h/2.
    pub fn half_width_mm(&self) -> f64 {
        0.5 * self.cells as f64 * self.cell_mm
    }

    /// Centre of cell index `i` along either axis (mm).
    pub fn offset_mm(&self, i: usize) -> f64 {
        (i as f64 - (self.cells / 2) as f64) * self.cell_mm
    }

    /// Mass of channel `c` in the cell (ix, iy).
    pub fn at(&self, c: usize, ix: usize, iy: usize) -> f64 {
        self.mass[c][iy * self.cells + ix]
    }

    /// Mean density (1/mm²) of channel `c` over the cell (ix, iy).
    pub fn density(&self, c: usize, ix: usize, iy: usize) -> f64 {
        self.at(c, ix, iy) / (self.cell_mm * self.cell_mm)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sss_bssrdf::{Medium, ModelKind, make_model};

    #[test]
    fn absurd_grids_are_refused_before_allocation() {
        let m = Medium::preset("skin1").unwrap();
        let model = make_model(ModelKind::BetterDipole, &m);
        // 10⁸ + 1 cells per side: 10¹⁶ cells × 24 bytes = 2.4·10¹⁷ bytes, would abort.
        let n = 100_000_001;
        let spec = Kernel2dSpec {
            cells: n,
            ..Default::default()
        };
        let e = Kernel2d::from_model(model.as_ref(), &spec)
            .unwrap_err()
            .to_string();
        assert!(e.contains("cells = 100000001"), "{e}");
        assert!(e.contains("240000004800000024 bytes"), "{e}");
        let e = Kernel2d::from_density(n, 0.1, 1, |_, _| [1.0; 3])
            .unwrap_err()
            .to_string();
        assert!(e.contains("240000004800000024 bytes"), "{e}");
        assert_eq!(grid_bytes(usize::MAX), u64::MAX);
        // Just over the limit is refused; a large grid under it is built (a constant density
        // sums to cells² · h²).
        assert!(Kernel2d::from_density(MAX_CELLS + 2, 1e-3, 1, |_, _| [1.0; 3]).is_err());
        let k = Kernel2d::from_density(1001, 1e-3, 1, |_, _| [1.0; 3]).unwrap();
        let expect = (1001.0f64 * 1e-3).powi(2);
        assert!((k.total[0] - expect).abs() < 1e-9 * expect, "{:?}", k.total);
    }

    #[test]
    fn kernel_is_symmetric_and_holds_the_requested_energy() {
        let m = make_model(ModelKind::BetterDipole, &Medium::preset("skin1").unwrap());
        let spec = Kernel2dSpec {
            cells: 41,
            ..Default::default()
        };
        let k = Kernel2d::from_model(m.as_ref(), &spec).unwrap();
        let n = k.cells;
        for c in 0..3 {
            let t = m.total_diffuse_reflectance(c);
            assert!(((k.total[c] - t) / t).abs() < 1e-13);
            // The square holds at least the disk's 99 % (the red channel sets the radius).
            assert!(
                k.captured_fraction[c] >= 0.99 - 1e-3,
                "{:?}",
                k.captured_fraction
            );
            assert!(k.captured_fraction[c] <= 1.0 + 1e-6);
            for iy in 0..n {
                for ix in 0..n {
                    let v = k.at(c, ix, iy);
                    assert!(v.is_finite() && v >= 0.0);
                    assert_eq!(v, k.at(c, iy, ix));
                    assert_eq!(v, k.at(c, n - 1 - ix, iy));
                }
            }
        }
        let unit = Kernel2d::from_model(
            m.as_ref(),
            &Kernel2dSpec {
                energy: Energy::Unit,
                ..spec
            },
        )
        .unwrap();
        assert!(unit.total.iter().all(|t| (t - 1.0).abs() < 1e-13));
        for bad in [
            Kernel2dSpec { cells: 40, ..spec },
            Kernel2dSpec {
                energy_fraction: 1.0,
                ..spec
            },
            Kernel2dSpec {
                subsamples: 0,
                ..spec
            },
        ] {
            assert!(Kernel2d::from_model(m.as_ref(), &bad).is_err());
        }
    }
}
