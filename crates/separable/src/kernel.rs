//! The representation every kernel of this crate shares, and the one the screen-space pass
//! ([`crate::screen_space`]) consumes: 1D taps (offset in mm, RGB weights), and a separable
//! kernel as a sum of (horizontal, vertical) 1D kernel pairs (Jimenez et al. 2015, Eq. 2:
//! (E ∗ A) = Σᵢ (E ∗ aᵢ) ∗ aᵢ), applied as one two-pass convolution per pair, summed.
//!
//! Energy convention: a tap weight is dimensionless (a 1D kernel's cell mass), and the 2D
//! kernel of a pair is h(x)·v(y), so its energy is (Σ h)(Σ v). The constructors of this crate
//! scale every kernel so that Σ over pairs of (Σ h)(Σ v) equals the model's total diffuse
//! reflectance per channel ([`Energy::TotalReflectance`]) or 1 ([`Energy::Unit`]).

use crate::Rgb;
use crate::error::{SeparableError, ensure};

/// What the weights of a kernel sum to, per channel (in 2D).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Energy {
    /// The model's total diffuse reflectance ∫ 2πr R_d(r) dr: the filter output is then the
    /// diffuse exitance E ∗ R_d itself (Jimenez et al. 2015, Eq. 1).
    #[default]
    TotalReflectance,
    /// 1 per channel: the filter only redistributes irradiance; the caller multiplies by an
    /// albedo.
    Unit,
}

/// One filter tap: a 1D offset and a weight per channel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tap {
    /// Offset along the pass's axis, in mm (world units on the surface).
    pub offset_mm: f64,
    /// Weight per channel (dimensionless: the kernel's mass the tap stands for).
    pub weight: Rgb,
}

/// A 1D kernel: taps sorted by offset.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Kernel1d {
    /// The taps, sorted by increasing offset.
    pub taps: Vec<Tap>,
}

impl Kernel1d {
    /// Sum of the weights per channel.
    pub fn sum(&self) -> Rgb {
        let mut s = [0.0; 3];
        for t in &self.taps {
            for (c, w) in s.iter_mut().zip(t.weight) {
                *c += w;
            }
        }
        s
    }

    /// Largest |offset| (mm); 0 for an empty kernel.
    pub fn radius_mm(&self) -> f64 {
        self.taps
            .iter()
            .map(|t| t.offset_mm.abs())
            .fold(0.0, f64::max)
    }

    /// The same taps with the weights of channel c multiplied by `scale[c]`.
    pub fn scaled(&self, scale: Rgb) -> Kernel1d {
        Kernel1d {
            taps: self
                .taps
                .iter()
                .map(|t| Tap {
                    offset_mm: t.offset_mm,
                    weight: [
                        t.weight[0] * scale[0],
                        t.weight[1] * scale[1],
                        t.weight[2] * scale[2],
                    ],
                })
                .collect(),
        }
    }

    /// The kernel in the layout of Jimenez's public separable SSS shader code (2012, and the
    /// 2015 paper's supplementary code): one `float4` per tap, `(r, g, b, offset)`, the
    /// centre tap (smallest |offset|) first and the others in increasing offset. Offsets stay
    /// in mm here; the shader code scales them by its own `sssWidth`.
    pub fn to_float4(&self) -> Vec<[f32; 4]> {
        let mut taps = self.taps.clone();
        if let Some(centre) = (0..taps.len())
            .min_by(|&a, &b| taps[a].offset_mm.abs().total_cmp(&taps[b].offset_mm.abs()))
        {
            let c = taps.remove(centre);
            taps.insert(0, c);
        }
        taps.iter()
            .map(|t| {
                [
                    t.weight[0] as f32,
                    t.weight[1] as f32,
                    t.weight[2] as f32,
                    t.offset_mm as f32,
                ]
            })
            .collect()
    }

    /// Whether every weight is finite.
    pub fn is_finite(&self) -> bool {
        self.taps
            .iter()
            .all(|t| t.offset_mm.is_finite() && t.weight.iter().all(|w| w.is_finite()))
    }
}

/// One separable summand h(x)·v(y) of a kernel: a horizontal and a vertical 1D kernel.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SeparableTerm {
    /// Applied along x (the first pass).
    pub horizontal: Kernel1d,
    /// Applied along y (the second pass).
    pub vertical: Kernel1d,
}

/// A kernel Σₖ hₖ(x)·vₖ(y) (Jimenez et al. 2015, Eq. 2), applied as one two-pass
/// convolution per term.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SeparableKernel {
    /// The separable terms (1 for the paper's rank-1 kernels, k for SVD rank k or k
    /// Gaussians).
    pub terms: Vec<SeparableTerm>,
    /// Half-width (mm) of the region the kernel was derived from: the screen-space pass uses
    /// it as the kernel's world size (footprint test, depth threshold, jitter radius). At
    /// least the largest tap offset.
    pub support_mm: f64,
}

impl SeparableKernel {
    /// A rank-1 kernel h(x)·h(y) from one set of 1D taps, scaled so the 2D energy is
    /// `energy` per channel: h = taps · √energyᶜ / Σ tapsᶜ. Errors if a channel of the taps
    /// sums to ≤ 0 while its energy is positive.
    pub fn symmetric(
        taps: &Kernel1d,
        energy: Rgb,
        support_mm: f64,
    ) -> Result<Self, SeparableError> {
        let s = taps.sum();
        let mut scale = [0.0; 3];
        for c in 0..3 {
            ensure(energy[c] >= 0.0 && energy[c].is_finite(), || {
                format!(
                    "energy[{c}] = {} must be finite and non-negative",
                    energy[c]
                )
            })?;
            if energy[c] == 0.0 {
                continue;
            }
            if !(s[c] > 1e-300) {
                return Err(SeparableError::ZeroEnergy { channel: c });
            }
            scale[c] = energy[c].sqrt() / s[c];
        }
        let h = taps.scaled(scale);
        Ok(SeparableKernel {
            terms: vec![SeparableTerm {
                horizontal: h.clone(),
                vertical: h,
            }],
            support_mm: support_mm.max(taps.radius_mm()),
        })
    }

    /// Σₖ (Σ hₖ)(Σ vₖ) per channel: the kernel's 2D energy.
    pub fn total_weight(&self) -> Rgb {
        let mut t = [0.0; 3];
        for term in &self.terms {
            let (h, v) = (term.horizontal.sum(), term.vertical.sum());
            for c in 0..3 {
                t[c] += h[c] * v[c];
            }
        }
        t
    }

    /// Largest tap offset of any pass (mm).
    pub fn radius_mm(&self) -> f64 {
        self.terms
            .iter()
            .map(|t| t.horizontal.radius_mm().max(t.vertical.radius_mm()))
            .fold(0.0, f64::max)
    }

    /// Number of 1D passes the screen-space filter makes (2 per term).
    pub fn passes(&self) -> usize {
        2 * self.terms.len()
    }

    /// Total number of taps over all passes (the cost per pixel).
    pub fn taps_per_pixel(&self) -> usize {
        self.terms
            .iter()
            .map(|t| t.horizontal.taps.len() + t.vertical.taps.len())
            .sum()
    }

    /// The same kernel rescaled so its 2D energy is `target` per channel (every term's
    /// horizontal weights of channel c multiplied by targetᶜ / totalᶜ). Errors if a channel's
    /// energy is not positive while its target is.
    pub fn with_energy(&self, target: Rgb) -> Result<SeparableKernel, SeparableError> {
        let total = self.total_weight();
        let mut scale = [0.0; 3];
        for c in 0..3 {
            ensure(target[c] >= 0.0 && target[c].is_finite(), || {
                format!(
                    "target[{c}] = {} must be finite and non-negative",
                    target[c]
                )
            })?;
            if target[c] == 0.0 {
                continue;
            }
            let abs: f64 = self
                .terms
                .iter()
                .map(|t| {
                    let h: f64 = t.horizontal.taps.iter().map(|x| x.weight[c].abs()).sum();
                    let v: f64 = t.vertical.taps.iter().map(|x| x.weight[c].abs()).sum();
                    h * v
                })
                .sum();
            if !(total[c] > 1e-12 * abs) || !(total[c] > 0.0) {
                return Err(SeparableError::ZeroEnergy { channel: c });
            }
            scale[c] = target[c] / total[c];
        }
        Ok(SeparableKernel {
            terms: self
                .terms
                .iter()
                .map(|t| SeparableTerm {
                    horizontal: t.horizontal.scaled(scale),
                    vertical: t.vertical.clone(),
                })
                .collect(),
            support_mm: self.support_mm,
        })
    }

    /// Whether every offset and weight is finite.
    pub fn is_finite(&self) -> bool {
        self.support_mm.is_finite()
            && self
                .terms
                .iter()
                .all(|t| t.horizontal.is_finite() && t.vertical.is_finite())
    }
}

/// A 1D profile on a uniform grid of `mass.len()` (odd) cells of width `cell_mm`, centred on
/// 0: cell i covers [xᵢ − cell/2, xᵢ + cell/2] with xᵢ = (i − (n−1)/2)·cell, and holds the
/// mass `mass[i]` (the integral of the 1D density over the cell) per channel; the density is
/// taken as constant inside a cell. This is the fine representation from which tap sets are
/// placed ([`crate::taps`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Profile1d {
    /// Cell width (mm).
    pub cell_mm: f64,
    /// Mass per cell and channel (odd count, symmetric grid around 0).
    pub mass: Vec<Rgb>,
}

impl Profile1d {
    /// A profile of `cells` (odd, ≥ 1) cells of width `cell_mm` > 0 whose masses are
    /// `cell_mass(a, b)` for the cell [a, b].
    pub fn from_cells(
        cells: usize,
        cell_mm: f64,
        mut cell_mass: impl FnMut(f64, f64) -> Rgb,
    ) -> Result<Self, SeparableError> {
        ensure(cells % 2 == 1, || format!("cells = {cells} must be odd"))?;
        ensure(cell_mm > 0.0 && cell_mm.is_finite(), || {
            format!("cell_mm = {cell_mm} must be positive and finite")
        })?;
        let c = (cells / 2) as f64;
        let mass = (0..cells)
            .map(|i| {
                let x = (i as f64 - c) * cell_mm;
                let m = cell_mass(x - 0.5 * cell_mm, x + 0.5 * cell_mm);
                m.map(|v| if v.is_finite() { v } else { 0.0 })
            })
            .collect();
        Ok(Profile1d { cell_mm, mass })
    }

    /// Number of cells.
    pub fn cells(&self) -> usize {
        self.mass.len()
    }

    /// Centre of cell `i` (mm).
    pub fn offset_mm(&self, i: usize) -> f64 {
        (i as f64 - (self.mass.len() / 2) as f64) * self.cell_mm
    }

    /// Half-width of the grid (mm): cells·cell/2.
    pub fn half_width_mm(&self) -> f64 {
        0.5 * self.mass.len() as f64 * self.cell_mm
    }

    /// Total mass per channel.
    pub fn total(&self) -> Rgb {
        let mut s = [0.0; 3];
        for m in &self.mass {
            for c in 0..3 {
                s[c] += m[c];
            }
        }
        s
    }

    /// Every cell as a tap at its centre.
    pub fn to_kernel1d(&self) -> Kernel1d {
        Kernel1d {
            taps: self
                .mass
                .iter()
                .enumerate()
                .map(|(i, m)| Tap {
                    offset_mm: self.offset_mm(i),
                    weight: *m,
                })
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn float4_layout_puts_the_centre_first() {
        let k = Kernel1d {
            taps: vec![
                Tap {
                    offset_mm: -1.0,
                    weight: [0.1, 0.2, 0.3],
                },
                Tap {
                    offset_mm: 0.0,
                    weight: [0.5, 0.4, 0.3],
                },
                Tap {
                    offset_mm: 1.0,
                    weight: [0.1, 0.2, 0.3],
                },
            ],
        };
        let f = k.to_float4();
        assert_eq!(f[0], [0.5, 0.4, 0.3, 0.0]);
        assert_eq!(f[1][3], -1.0);
        assert_eq!(f[2][3], 1.0);
    }

    #[test]
    fn energy_rescaling_hits_the_target() {
        let taps = Kernel1d {
            taps: vec![
                Tap {
                    offset_mm: -0.5,
                    weight: [1.0, 2.0, 3.0],
                },
                Tap {
                    offset_mm: 0.5,
                    weight: [1.0, 2.0, 3.0],
                },
            ],
        };
        let k = SeparableKernel::symmetric(&taps, [0.4, 0.2, 0.1], 1.0).unwrap();
        let t = k.total_weight();
        for (a, b) in t.iter().zip([0.4, 0.2, 0.1]) {
            assert!((a - b).abs() < 1e-15);
        }
        let u = k.with_energy([1.0; 3]).unwrap().total_weight();
        assert!(u.iter().all(|x| (x - 1.0).abs() < 1e-15));
        let zero = Kernel1d {
            taps: vec![Tap {
                offset_mm: 0.0,
                weight: [1.0, 0.0, 1.0],
            }],
        };
        assert_eq!(
            SeparableKernel::symmetric(&zero, [1.0; 3], 0.0),
            Err(SeparableError::ZeroEnergy { channel: 1 })
        );
    }
}
