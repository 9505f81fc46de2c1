//! The pre-integrated separable kernel (Jimenez et al. 2015, §4, Eq. 4–5).
//!
//! For additively separable irradiance E(x, y) = E₁(x) + E₂(y) (straight shadow edges of
//! any axis-aligned orientation, 1D signals), the exact exitance is
//! M_e = ∫E₁(x′) a_p(x − x′) dx′ + ∫E₂(y′) a_p(y − y′) dy′ with the pre-integrated profile
//! a_p(x) = ∫ R_d(x, y) dy (Eq. 4), and the rank-1 kernel
//! A_p(x, y) = a_p(x) a_p(y) / ‖R_d‖₁ (Eq. 5) reproduces it exactly because
//! ‖a_p‖₁ = ‖R_d‖₁.
//!
//! Discretely: a_p's cell masses are the column sums of the [`Kernel2d`] mass matrix, so the
//! identity holds to rounding against the discrete 2D convolution with the same kernel
//! ([`crate::convolve2d::grid_full`]); with fewer taps ([`TapPlacement::Importance`]) it
//! holds for the tap set's own 2D kernel, and approximately for the fine kernel.

use crate::error::SeparableError;
use crate::kernel::{Profile1d, SeparableKernel};
use crate::kernel2d::Kernel2d;
use crate::taps::{self, TapPlacement};

/// The pre-integrated profile a_p (Eq. 4) of `kernel`: mass of cell i = Σⱼ K\[j\]\[i\], the
/// kernel integrated over y for the column x = offset(i). Its total equals the kernel's.
pub fn profile(kernel: &Kernel2d) -> Profile1d {
    let n = kernel.cells;
    let mass = (0..n)
        .map(|ix| std::array::from_fn(|c| (0..n).map(|iy| kernel.at(c, ix, iy)).sum()))
        .collect();
    Profile1d {
        cell_mm: kernel.cell_mm,
        mass,
    }
}

/// The pre-integrated separable kernel A_p = a_p(x) a_p(y) / ‖R_d‖₁ (Eq. 5), one term with
/// h = v = taps(a_p) / √‖R_d‖₁ per channel, so its energy equals the kernel's
/// ([`Kernel2d::total`]).
pub fn kernel(
    kernel: &Kernel2d,
    placement: TapPlacement,
) -> Result<SeparableKernel, SeparableError> {
    let p = profile(kernel);
    let t = taps::place(&p, placement)?;
    SeparableKernel::symmetric(&t, kernel.total, kernel.half_width_mm())
}
