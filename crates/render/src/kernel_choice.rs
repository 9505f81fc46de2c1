//! Choosing and building a separable screen-space kernel (Jimenez et al. 2015) for a model:
//! which kernel ([`KernelMethod`]), its taps and filter options ([`SeparableSettings`]), and
//! [`build_kernel`], shared by the `separable` integrator, `sss kernel` and `sss filter`.
//! Kernels come from `sss-separable`.
//!
//! `KernelMethod::Exact2d` replaces the separable pass by the brute-force 2D screen-space
//! convolution with the full discretised kernel at the same footprint: the reference of the
//! separable approximation itself (as opposed to the world-space `exact` reference, which
//! also includes what screen space cannot see).

use sss_bssrdf::Bssrdf;
use sss_separable::{
    FilterOptions, Kernel2d, Kernel2dSpec, SeparableError, SeparableKernel, TapPlacement, artist,
    gaussians, guided, preintegrated, svd,
};
use std::fmt;
use std::str::FromStr;

/// Which separable kernel to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum KernelMethod {
    /// Pre-integrated rank-1 kernel (Eq. 4-5).
    Preintegrated,
    /// Rank-1 SVD.
    Svd1,
    /// Rank-3 SVD (6 passes).
    Svd3,
    /// Rank-6 SVD (12 passes).
    Svd6,
    /// The artist-friendly two-Gaussian model (Eq. 6) fitted to the material.
    Artist,
    /// Guided rank-1 optimisation (Appendix A), exponent `k`.
    Guided,
    /// One Gaussian (d'Eon et al. 2007).
    Gaussians1,
    /// Six Gaussians (12 passes).
    Gaussians6,
    /// The exact 2D screen-space convolution with the full kernel (the separable kernels'
    /// reference).
    Exact2d,
}

impl KernelMethod {
    /// Every method, in report order.
    pub const ALL: [KernelMethod; 9] = [
        KernelMethod::Preintegrated,
        KernelMethod::Svd1,
        KernelMethod::Svd3,
        KernelMethod::Svd6,
        KernelMethod::Artist,
        KernelMethod::Guided,
        KernelMethod::Gaussians1,
        KernelMethod::Gaussians6,
        KernelMethod::Exact2d,
    ];

    /// The command-line names of [`KernelMethod::ALL`], in its order.
    pub const NAMES: [&'static str; 9] = {
        let mut names = [""; 9];
        let mut i = 0;
        while i < names.len() {
            names[i] = KernelMethod::ALL[i].name();
            i += 1;
        }
        names
    };

    /// The names of the separable kernels: [`KernelMethod::NAMES`] but `exact2d` (which
    /// `sss kernel` cannot export).
    pub fn separable_names() -> Vec<&'static str> {
        KernelMethod::ALL
            .iter()
            .filter(|k| k.is_separable())
            .map(|k| k.name())
            .collect()
    }

    /// Whether this is a separable kernel (every method but [`KernelMethod::Exact2d`]).
    pub const fn is_separable(self) -> bool {
        !matches!(self, KernelMethod::Exact2d)
    }

    /// The command-line name.
    pub const fn name(self) -> &'static str {
        match self {
            KernelMethod::Preintegrated => "preintegrated",
            KernelMethod::Svd1 => "svd1",
            KernelMethod::Svd3 => "svd3",
            KernelMethod::Svd6 => "svd6",
            KernelMethod::Artist => "artist",
            KernelMethod::Guided => "guided",
            KernelMethod::Gaussians1 => "gaussians1",
            KernelMethod::Gaussians6 => "gaussians6",
            KernelMethod::Exact2d => "exact2d",
        }
    }
}

impl fmt::Display for KernelMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for KernelMethod {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        KernelMethod::ALL
            .iter()
            .copied()
            .find(|k| k.name() == s)
            .ok_or_else(|| {
                format!(
                    "unknown kernel `{s}` (known: {})",
                    KernelMethod::NAMES.join(", ")
                )
            })
    }
}

/// Settings of the separable integrator.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SeparableSettings {
    /// The kernel.
    pub kernel: KernelMethod,
    /// Taps per 1D pass.
    pub taps: usize,
    /// Place taps by importance (the dominant channel's CDF) rather than uniformly. SVD terms
    /// change sign and are always placed uniformly.
    pub importance: bool,
    /// Guided optimisation exponent k in [0, 4].
    pub k: f64,
    /// Fraction of the kernel support within which taps are rotated per pixel (0: no jitter).
    pub jitter: f32,
}

impl SeparableSettings {
    /// Checks the options shared by `sss render`, `sss filter` and `sss kernel`: taps in
    /// 1..=1025, k in [0, 4], jitter in [0, 1]. Messages name the flag.
    pub fn check(&self) -> Result<(), crate::Error> {
        check_separable_options(self.taps, self.k, self.jitter)
    }
}

/// Checks tap count, guided exponent and jitter radius (see [`SeparableSettings::check`]).
pub fn check_separable_options(taps: usize, k: f64, jitter: f32) -> Result<(), crate::Error> {
    use crate::Error;
    if taps == 0 || taps > 1025 {
        return Err(Error::Input(format!(
            "--taps must lie in 1..=1025, got {taps}"
        )));
    }
    if !(0.0..=4.0).contains(&k) {
        return Err(Error::Input(format!("--k must lie in [0, 4], got {k}")));
    }
    if !(0.0..=1.0).contains(&jitter) {
        return Err(Error::Input(format!(
            "--jitter must lie in [0, 1], got {jitter}"
        )));
    }
    Ok(())
}

impl Default for SeparableSettings {
    /// The declared defaults of the `separable` method's options
    /// ([`crate::integrators::separable::OPTIONS`]; `--uniform-taps` off).
    fn default() -> Self {
        use crate::integrators::options::declared;
        use crate::integrators::separable::OPTIONS;
        SeparableSettings {
            kernel: declared(&OPTIONS, "kernel"),
            taps: declared(&OPTIONS, "taps"),
            importance: true,
            k: declared(&OPTIONS, "k"),
            jitter: declared(&OPTIONS, "jitter"),
        }
    }
}

/// A material's kernel: the separable one, or the full 2D grid for `Exact2d`.
pub enum MaterialKernel {
    /// Two 1D passes per term.
    Separable(SeparableKernel),
    /// The full discretised kernel.
    Full(Kernel2d),
}

/// Builds the kernel of `model` for `settings`; its weights sum to the model's total diffuse
/// reflectance per channel.
pub fn build_kernel(
    model: &dyn Bssrdf,
    settings: &SeparableSettings,
) -> Result<MaterialKernel, SeparableError> {
    let k2 = Kernel2d::from_model(model, &Kernel2dSpec::default())?;
    let n = settings.taps.max(1);
    let placement = if settings.importance {
        TapPlacement::Importance(n)
    } else {
        TapPlacement::Uniform(n)
    };
    let total = k2.total;
    let kernel = match settings.kernel {
        KernelMethod::Exact2d => return Ok(MaterialKernel::Full(k2)),
        KernelMethod::Preintegrated => preintegrated::kernel(&k2, placement)?,
        KernelMethod::Svd1 | KernelMethod::Svd3 | KernelMethod::Svd6 => {
            let rank = match settings.kernel {
                KernelMethod::Svd1 => 1,
                KernelMethod::Svd3 => 3,
                _ => 6,
            };
            svd::decompose(&k2)?.separable(rank, TapPlacement::Uniform(n))?
        }
        KernelMethod::Artist => {
            let fit = artist::fit(&preintegrated::profile(&k2))?;
            artist::kernel(&fit.params, total, placement)?
        }
        KernelMethod::Guided => {
            let opts = guided::GuidedOptions {
                k: settings.k,
                ..guided::GuidedOptions::default()
            };
            guided::optimize(&k2, &opts)?.kernel(placement)?
        }
        KernelMethod::Gaussians1 | KernelMethod::Gaussians6 => {
            let count = if settings.kernel == KernelMethod::Gaussians1 {
                1
            } else {
                6
            };
            let fits = gaussians::fit_model(model, count)?;
            let fit = fits
                .last()
                .ok_or_else(|| SeparableError::InvalidArgument("no Gaussian fit".into()))?;
            fit.kernel(total, placement)?
        }
    };
    Ok(MaterialKernel::Separable(kernel))
}

/// The filter options of a render.
pub fn filter_options(settings: &SeparableSettings, seed: u64) -> FilterOptions {
    FilterOptions {
        jitter_radius: settings.jitter,
        seed,
        ..FilterOptions::default()
    }
}
