//! Model accuracy pinned, not ordered.
//!
//! Every model's relative L2 error against the Monte Carlo reference, and the ratio of its
//! total diffuse reflectance to the Monte Carlo total, are pinned per preset and channel to
//! today's values; the standard dipole's total is checked against Jensen et al. 2001's
//! closed form with the Egan-Hilgeman F_dr the paper uses; the Monte Carlo reference's length
//! scale is checked by a scaling law and by the mean exit radius of photon beam diffusion.
//!
//! # How the Monte Carlo comparison is measured
//! As `cargo xtask compare` does it (crates/compare/src/{profiles,metrics,reference}.rs): one
//! single-channel simulation per (preset, channel), [`BINS`] linear bins over [0, r_max] with
//! r_max the standard dipole's radius holding 99 % of its reflectance; the model's *area
//! averages* over the same annuli; the relative L2 error of the energy per bin,
//! ‖A(model − mc)‖ / ‖A·mc‖. The standard and better dipoles are measured against the
//! multiple-scattering part of the tally (total minus photons that escaped after one
//! collision); photon beam diffusion, normalized diffusion, `mc-table` and the directional
//! dipole against the full tally (the directional dipole puts a source of strength 1, not α′, at the ray's
//! first scattering event — Frisvad et al. 2014, Eq. 20 — so it stands for all scattered light;
//! `WalkPart::All` in crates/compare/src/profiles/registry.rs).
//!
//! # Margins
//! The simulation is seeded ([`SEED`]) and bit-identical for any thread count, so every value
//! here is deterministic. Each pin carries σ, the standard deviation of the value over seeds
//! 1..=8 at the same photon count (measured once, typed in below). A pinned value v₀ passes
//! when |v − v₀| ≤ 3σ + ρ·v₀:
//! - 3σ: a change of the random stream (another seed, reordered draws, a different chunking)
//!   that keeps the Monte Carlo distribution moves a value by about σ, which 3σ absorbs for
//!   ~99.7 % of the values. (With 360 values, a re-seed is expected to trip about two in three
//!   runs of this file: re-measure the table after changing the Monte Carlo stream.)
//! - ρ = [`REL_ERR_SLACK`] (2 %) for errors and [`REL_RATIO_SLACK`] (0.2 %) for total ratios:
//!   room for numerics that do not change a model (quadrature orders, libm), which move these
//!   values by < 1e-6 today. They are deliberately far below the 15 % one might pick: a 10 %
//!   change of the standard dipole's z_v moves its L2 error by only 1-9 % and its total by
//!   1-3.5 %, and a 20 % error in C₂ moves the better dipole's error by 2-6 %.
//! - Both sides are checked: several plausible bugs make errors *smaller*
//!   (a Monte Carlo step 10 % short halves photon beam diffusion's error on marble red; C₂ × 1.2
//!   lowers it by 20-35 % on every preset), so an upper bound alone would miss them.
//!
//! # Cost
//! Every preset of Jensen et al. 2001 Table 2 ([`presets::PRESETS`]) is pinned. Photons per
//! channel ([`photons`]): 131 072 for skin1, skin2 and ketchup, 65 536 for marble and potato,
//! 32 768 for the chickens, and fewer for the brightest media, whose walks are long (thousands
//! of collisions at albedos 0.9997-1): 8192 for apple and skim milk, 4096 for whole milk, 2048
//! for cream and 1024 for spectralon (albedo exactly 1). The whole file takes ~22 s of CPU
//! in release (~11 s on 2 idle cores), the seven added presets ~6 s of it. At these
//! counts σ is 0.6-3 % of the errors of the standard and better dipoles and of normalized
//! diffusion on skin1, skin2, ketchup, potato and marble, 5-8 % of photon beam diffusion's
//! (whose error, ~0.06, is close to the Monte Carlo noise floor; ~25 % on ketchup green and
//! blue), and 0.1-1.7 % of the total ratios; the media simulated with few photons have σ up to
//! a few times larger, so their pins are looser. Measured: the better dipole with α′ for α′²
//! fails 32 values on six presets, the standard dipole with z_v × 1.1 fails 18 on eight.

use sss_bssrdf::monte_carlo::{BinSpacing, WalkConfig, WalkProfile, simulate};
use sss_bssrdf::quadrature::integrate_radial_range;
use sss_bssrdf::*;

/// The Monte Carlo seed of every pinned value.
const SEED: u64 = 1;
/// Linear radial bins per channel over [0, r_max].
const BINS: usize = 32;
/// Relative slack of the pinned L2 errors (see the module documentation).
const REL_ERR_SLACK: f64 = 0.02;
/// Relative slack of the pinned total ratios (see the module documentation).
const REL_RATIO_SLACK: f64 = 0.002;

const SD: ModelKind = ModelKind::StandardDipole;
const BD: ModelKind = ModelKind::BetterDipole;
const DD: ModelKind = ModelKind::DirectionalDipole;
const PBD: ModelKind = ModelKind::PhotonBeamDiffusion;
const CB: ModelKind = ModelKind::Burley;
const MCT: ModelKind = ModelKind::McTable;

/// One pinned (preset, channel, model): today's relative L2 error against the Monte Carlo
/// reference and its seed-to-seed standard deviation, today's ratio of the model's total
/// diffuse reflectance to the Monte Carlo total (of the same part) and its standard deviation.
struct Pin {
    preset: &'static str,
    ch: usize,
    kind: ModelKind,
    err: f64,
    err_sd: f64,
    ratio: f64,
    ratio_sd: f64,
}

const fn pin(
    preset: &'static str,
    ch: usize,
    kind: ModelKind,
    err: f64,
    err_sd: f64,
    ratio: f64,
    ratio_sd: f64,
) -> Pin {
    Pin {
        preset,
        ch,
        kind,
        err,
        err_sd,
        ratio,
        ratio_sd,
    }
}

/// Measured with seeds 1..=8 (value: seed 1; σ: standard deviation over the eight), except the
/// directional dipole's rows of skin1, ketchup, skin2, potato and marble (σ over seeds 1..=4,
/// measured when it moved to the full tally).
/// The `mc-table` rows (the tabulated random walk itself) have errors at the noise floor of
/// these references (0.009-0.08: their seed-to-seed σ is a fifth to a half of the error) and
/// total ratios within 1 % of 1 except ketchup blue (albedo 0.02, +2 %: the table interpolates
/// between its albedo rows 0 and 0.078 there).
/// Ketchup's green and blue channels scatter so little (albedo 0.07 and 0.02) that their
/// multiple-scattering tally is ~1e-4 of the light: the standard and directional dipoles'
/// errors there (21 and 71; 18 and 61 against the full tally, with totals 27 and 89 times the
/// Monte Carlo's) are pinned as what the models do there, not as meaningful accuracies.
#[rustfmt::skip]
const PINS: &[Pin] = &[
    // skin1
    pin("skin1", 0, SD, 0.388714, 0.0037, 1.1902, 0.0033),
    pin("skin1", 0, BD, 0.224928, 0.0027, 1.10493, 0.0031),
    pin("skin1", 0, DD, 0.502406, 0.0047, 1.44956, 0.0033),
    pin("skin1", 0, PBD, 0.059537, 0.0028, 1.05424, 0.0023),
    pin("skin1", 0, CB, 0.356656, 0.0037, 1.05424, 0.0023),
    pin("skin1", 1, SD, 0.749819, 0.013, 1.52302, 0.0085),
    pin("skin1", 1, BD, 0.279996, 0.0092, 1.09048, 0.0061),
    pin("skin1", 1, DD, 0.822599, 0.008, 1.83914, 0.0087),
    pin("skin1", 1, PBD, 0.061767, 0.0047, 1.0732, 0.0054),
    pin("skin1", 1, CB, 0.308547, 0.0087, 1.0732, 0.0054),
    pin("skin1", 2, SD, 1.27887, 0.0098, 2.04952, 0.0087),
    pin("skin1", 2, BD, 0.342055, 0.0068, 1.09737, 0.0047),
    pin("skin1", 2, DD, 1.23302, 0.0091, 2.44149, 0.0098),
    pin("skin1", 2, PBD, 0.058904, 0.0042, 1.08207, 0.0044),
    pin("skin1", 2, CB, 0.186827, 0.0076, 1.08207, 0.0044),
    pin("skin1", 0, MCT, 0.011084, 0.0019, 1.00196, 0.0021),
    pin("skin1", 1, MCT, 0.009848, 0.0028, 1.00392, 0.005),
    pin("skin1", 2, MCT, 0.017222, 0.0027, 0.994083, 0.0041),
    // ketchup
    pin("ketchup", 0, SD, 1.02705, 0.01, 1.7915, 0.011),
    pin("ketchup", 0, BD, 0.315581, 0.0054, 1.08276, 0.0066),
    pin("ketchup", 0, DD, 1.04783, 0.0085, 2.15484, 0.0066),
    pin("ketchup", 0, PBD, 0.060206, 0.0042, 1.0775, 0.0067),
    pin("ketchup", 0, CB, 0.238546, 0.0088, 1.0775, 0.0067),
    pin("ketchup", 1, SD, 21.1695, 0.31, 21.9457, 0.27),
    pin("ketchup", 1, BD, 0.526139, 0.0077, 1.24622, 0.015),
    pin("ketchup", 1, DD, 18.3996, 0.14, 27.4551, 0.26),
    pin("ketchup", 1, PBD, 0.021871, 0.0064, 1.02692, 0.0066),
    pin("ketchup", 1, CB, 0.238002, 0.0057, 1.02692, 0.0066),
    pin("ketchup", 2, SD, 71.1196, 1.5, 72.0023, 1.2),
    pin("ketchup", 2, BD, 0.55142, 0.011, 1.2494, 0.021),
    pin("ketchup", 2, DD, 60.9446, 0.51, 89.0987, 0.86),
    pin("ketchup", 2, PBD, 0.034397, 0.0087, 1.0407, 0.0096),
    pin("ketchup", 2, CB, 0.25236, 0.0092, 1.0407, 0.0096),
    pin("ketchup", 0, MCT, 0.0112, 0.0044, 0.996841, 0.0062),
    pin("ketchup", 1, MCT, 0.019263, 0.0043, 1.00524, 0.0065),
    pin("ketchup", 2, MCT, 0.030098, 0.0069, 1.0206, 0.0094),
    // skin2
    pin("skin2", 0, SD, 0.281662, 0.0062, 1.11579, 0.0023),
    pin("skin2", 0, BD, 0.203783, 0.0028, 1.10731, 0.0023),
    pin("skin2", 0, DD, 0.393847, 0.0031, 1.33477, 0.0014),
    pin("skin2", 0, PBD, 0.059349, 0.0028, 1.04561, 0.0017),
    pin("skin2", 0, CB, 0.386873, 0.0043, 1.04561, 0.0017),
    pin("skin2", 1, SD, 0.385069, 0.0064, 1.194, 0.003),
    pin("skin2", 1, BD, 0.220903, 0.0042, 1.1066, 0.0028),
    pin("skin2", 1, DD, 0.499405, 0.006, 1.45114, 0.0023),
    pin("skin2", 1, PBD, 0.057014, 0.0046, 1.05375, 0.0024),
    pin("skin2", 1, CB, 0.352671, 0.0088, 1.05375, 0.0024),
    pin("skin2", 2, SD, 0.486873, 0.0068, 1.28084, 0.0054),
    pin("skin2", 2, BD, 0.234857, 0.0049, 1.10081, 0.0047),
    pin("skin2", 2, DD, 0.598352, 0.0043, 1.56053, 0.005),
    pin("skin2", 2, PBD, 0.061284, 0.0032, 1.06142, 0.003),
    pin("skin2", 2, CB, 0.355799, 0.0067, 1.06142, 0.003),
    pin("skin2", 0, MCT, 0.012415, 0.0018, 0.999779, 0.0017),
    pin("skin2", 1, MCT, 0.00989, 0.0037, 1.00141, 0.0023),
    pin("skin2", 2, MCT, 0.016189, 0.0025, 1.00445, 0.0028),
    // potato
    pin("potato", 0, SD, 0.202807, 0.0057, 1.0931, 0.0015),
    pin("potato", 0, BD, 0.177273, 0.0057, 1.09931, 0.0015),
    pin("potato", 0, DD, 0.348554, 0.0041, 1.28921, 0.0015),
    pin("potato", 0, PBD, 0.056202, 0.0027, 1.04227, 0.0012),
    pin("potato", 0, CB, 0.445692, 0.005, 1.04227, 0.0012),
    pin("potato", 1, SD, 0.27631, 0.0047, 1.11756, 0.003),
    pin("potato", 1, BD, 0.197779, 0.004, 1.10706, 0.003),
    pin("potato", 1, DD, 0.404478, 0.0071, 1.34509, 0.0036),
    pin("potato", 1, PBD, 0.065355, 0.0046, 1.05071, 0.003),
    pin("potato", 1, CB, 0.397392, 0.0083, 1.05071, 0.003),
    pin("potato", 2, SD, 0.809911, 0.0098, 1.57646, 0.0065),
    pin("potato", 2, BD, 0.289983, 0.0094, 1.09177, 0.0045),
    pin("potato", 2, DD, 0.86865, 0.011, 1.89796, 0.011),
    pin("potato", 2, PBD, 0.06524, 0.0044, 1.07575, 0.0049),
    pin("potato", 2, CB, 0.298678, 0.012, 1.07575, 0.0049),
    pin("potato", 0, MCT, 0.014298, 0.002, 0.999619, 0.0012),
    pin("potato", 1, MCT, 0.017567, 0.0027, 1.00436, 0.0029),
    pin("potato", 2, MCT, 0.016843, 0.0054, 1.00412, 0.0045),
    // marble
    pin("marble", 0, SD, 0.189325, 0.0051, 1.0861, 0.0017),
    pin("marble", 0, BD, 0.148572, 0.0036, 1.09261, 0.0017),
    pin("marble", 0, DD, 0.347425, 0.006, 1.14537, 0.001),
    pin("marble", 0, PBD, 0.062404, 0.0035, 1.04024, 0.00074),
    pin("marble", 0, CB, 0.503217, 0.0055, 1.04024, 0.00074),
    pin("marble", 1, SD, 0.190895, 0.0048, 1.0882, 0.0015),
    pin("marble", 1, BD, 0.160744, 0.0034, 1.09526, 0.0015),
    pin("marble", 1, DD, 0.338982, 0.001, 1.18535, 0.0002),
    pin("marble", 1, PBD, 0.055016, 0.0032, 1.03889, 0.001),
    pin("marble", 1, CB, 0.473771, 0.0058, 1.03889, 0.001),
    pin("marble", 2, SD, 0.197622, 0.0047, 1.08888, 0.0025),
    pin("marble", 2, BD, 0.168541, 0.0039, 1.0959, 0.0025),
    pin("marble", 2, DD, 0.346916, 0.0028, 1.23337, 0.0015),
    pin("marble", 2, PBD, 0.057682, 0.0036, 1.04133, 0.002),
    pin("marble", 2, CB, 0.466849, 0.0076, 1.04133, 0.002),
    pin("marble", 0, MCT, 0.010404, 0.0013, 1.00081, 0.00071),
    pin("marble", 1, MCT, 0.00876, 0.0018, 0.998326, 0.00098),
    pin("marble", 2, MCT, 0.011193, 0.0023, 0.999829, 0.002),
    // apple
    pin("apple", 0, SD, 0.204906, 0.013, 1.08811, 0.0018),
    pin("apple", 0, BD, 0.171516, 0.012, 1.09503, 0.0018),
    pin("apple", 0, DD, 0.369971, 0.015, 1.17715, 0.0038),
    pin("apple", 0, PBD, 0.082512, 0.01, 1.04615, 0.0034),
    pin("apple", 0, CB, 0.517958, 0.021, 1.04615, 0.0034),
    pin("apple", 1, SD, 0.176417, 0.015, 1.07604, 0.0081),
    pin("apple", 1, BD, 0.14706, 0.0063, 1.08295, 0.0082),
    pin("apple", 1, DD, 0.341555, 0.0044, 1.17288, 0.0029),
    pin("apple", 1, PBD, 0.059787, 0.0041, 1.03581, 0.0026),
    pin("apple", 1, CB, 0.489112, 0.0066, 1.03581, 0.0026),
    pin("apple", 2, SD, 0.297202, 0.022, 1.12379, 0.011),
    pin("apple", 2, BD, 0.205135, 0.015, 1.08918, 0.01),
    pin("apple", 2, DD, 0.435, 0.014, 1.37635, 0.0094),
    pin("apple", 2, PBD, 0.070549, 0.01, 1.04531, 0.0071),
    pin("apple", 2, CB, 0.374608, 0.019, 1.04531, 0.0071),
    pin("apple", 0, MCT, 0.03059, 0.0063, 1.00562, 0.0033),
    pin("apple", 1, MCT, 0.025847, 0.0068, 0.995539, 0.0025),
    pin("apple", 2, MCT, 0.043743, 0.01, 0.996649, 0.0068),
    // chicken1
    pin("chicken1", 0, SD, 0.526734, 0.012, 1.31897, 0.0077),
    pin("chicken1", 0, BD, 0.250771, 0.0032, 1.09399, 0.0064),
    pin("chicken1", 0, DD, 0.621201, 0.011, 1.5921, 0.009),
    pin("chicken1", 0, PBD, 0.053195, 0.0072, 1.05135, 0.0059),
    pin("chicken1", 0, CB, 0.322676, 0.013, 1.05135, 0.0059),
    pin("chicken1", 1, SD, 1.07758, 0.02, 1.85075, 0.014),
    pin("chicken1", 1, BD, 0.338803, 0.0071, 1.08886, 0.0083),
    pin("chicken1", 1, DD, 1.06784, 0.021, 2.20741, 0.022),
    pin("chicken1", 1, PBD, 0.059673, 0.0084, 1.07537, 0.011),
    pin("chicken1", 1, CB, 0.214205, 0.015, 1.07537, 0.011),
    pin("chicken1", 2, SD, 1.36752, 0.025, 2.10527, 0.017),
    pin("chicken1", 2, BD, 0.374434, 0.014, 1.10549, 0.009),
    pin("chicken1", 2, DD, 1.30358, 0.02, 2.53829, 0.024),
    pin("chicken1", 2, PBD, 0.079602, 0.0089, 1.10253, 0.011),
    pin("chicken1", 2, CB, 0.199098, 0.012, 1.10253, 0.011),
    pin("chicken1", 0, MCT, 0.028016, 0.0058, 0.99297, 0.0056),
    pin("chicken1", 1, MCT, 0.032732, 0.0036, 0.99321, 0.01),
    pin("chicken1", 2, MCT, 0.029086, 0.0068, 1.01192, 0.0097),
    // chicken2
    pin("chicken2", 0, SD, 0.526641, 0.011, 1.30689, 0.0083),
    pin("chicken2", 0, BD, 0.247441, 0.0076, 1.09446, 0.007),
    pin("chicken2", 0, DD, 0.627553, 0.0053, 1.59209, 0.0049),
    pin("chicken2", 0, PBD, 0.062459, 0.0032, 1.05976, 0.0033),
    pin("chicken2", 0, CB, 0.350612, 0.0072, 1.05976, 0.0033),
    pin("chicken2", 1, SD, 1.05702, 0.018, 1.81267, 0.011),
    pin("chicken2", 1, BD, 0.316714, 0.012, 1.08154, 0.0069),
    pin("chicken2", 1, DD, 1.08026, 0.014, 2.18625, 0.013),
    pin("chicken2", 1, PBD, 0.071986, 0.0067, 1.07973, 0.0064),
    pin("chicken2", 1, CB, 0.246566, 0.0097, 1.07973, 0.0064),
    pin("chicken2", 2, SD, 1.54988, 0.02, 2.31027, 0.017),
    pin("chicken2", 2, BD, 0.389209, 0.0091, 1.10904, 0.0082),
    pin("chicken2", 2, DD, 1.43418, 0.024, 2.75955, 0.022),
    pin("chicken2", 2, PBD, 0.061937, 0.0086, 1.08962, 0.0087),
    pin("chicken2", 2, CB, 0.149849, 0.014, 1.08962, 0.0087),
    pin("chicken2", 0, MCT, 0.022249, 0.0039, 1.00144, 0.0031),
    pin("chicken2", 1, MCT, 0.032558, 0.0043, 0.998097, 0.006),
    pin("chicken2", 2, MCT, 0.021224, 0.0049, 0.996502, 0.008),
    // cream
    pin("cream", 0, SD, 0.142333, 0.014, 1.0862, 0.0043),
    pin("cream", 0, BD, 0.112227, 0.0097, 1.08779, 0.0043),
    pin("cream", 0, DD, 0.321334, 0.015, 1.02408, 0.0012),
    pin("cream", 0, PBD, 0.052961, 0.013, 1.02408, 0.0012),
    pin("cream", 0, CB, 0.482914, 0.019, 1.02408, 0.0012),
    pin("cream", 1, SD, 0.222894, 0.029, 1.08473, 0.0092),
    pin("cream", 1, BD, 0.144729, 0.017, 1.09019, 0.0093),
    pin("cream", 1, DD, 0.379764, 0.027, 1.1088, 0.004),
    pin("cream", 1, PBD, 0.092677, 0.018, 1.04273, 0.0038),
    pin("cream", 1, CB, 0.560265, 0.038, 1.04273, 0.0038),
    pin("cream", 2, SD, 0.263265, 0.033, 1.08862, 0.012),
    pin("cream", 2, BD, 0.182018, 0.028, 1.09278, 0.012),
    pin("cream", 2, DD, 0.418483, 0.038, 1.31045, 0.012),
    pin("cream", 2, PBD, 0.117374, 0.02, 1.05149, 0.0094),
    pin("cream", 2, CB, 0.518588, 0.058, 1.05149, 0.0094),
    pin("cream", 0, MCT, 0.021723, 0.0053, 1.00031, 0.0012),
    pin("cream", 1, MCT, 0.046535, 0.006, 1.0042, 0.0036),
    pin("cream", 2, MCT, 0.081051, 0.014, 1.00741, 0.009),
    // skimmilk
    pin("skimmilk", 0, SD, 0.200834, 0.0091, 1.0944, 0.0059),
    pin("skimmilk", 0, BD, 0.166341, 0.014, 1.10155, 0.0059),
    pin("skimmilk", 0, DD, 0.350787, 0.0088, 1.21801, 0.0069),
    pin("skimmilk", 0, PBD, 0.065788, 0.0089, 1.04506, 0.0059),
    pin("skimmilk", 0, CB, 0.478568, 0.0098, 1.04506, 0.0059),
    pin("skimmilk", 1, SD, 0.200375, 0.0095, 1.08595, 0.0065),
    pin("skimmilk", 1, BD, 0.173965, 0.0059, 1.09304, 0.0066),
    pin("skimmilk", 1, DD, 0.340432, 0.012, 1.20927, 0.004),
    pin("skimmilk", 1, PBD, 0.059089, 0.0077, 1.03524, 0.0034),
    pin("skimmilk", 1, CB, 0.464679, 0.016, 1.03524, 0.0034),
    pin("skimmilk", 2, SD, 0.252183, 0.013, 1.1165, 0.0065),
    pin("skimmilk", 2, BD, 0.212095, 0.013, 1.11694, 0.0065),
    pin("skimmilk", 2, DD, 0.373723, 0.014, 1.32766, 0.008),
    pin("skimmilk", 2, PBD, 0.070207, 0.0088, 1.05569, 0.0063),
    pin("skimmilk", 2, CB, 0.405047, 0.025, 1.05569, 0.0063),
    pin("skimmilk", 0, MCT, 0.027052, 0.01, 1.00377, 0.0056),
    pin("skimmilk", 1, MCT, 0.0213, 0.004, 0.994287, 0.0033),
    pin("skimmilk", 2, MCT, 0.041809, 0.0091, 1.0103, 0.0061),
    // spectralon
    pin("spectralon", 0, SD, 0.14232, 0.024, 1.09863, 0.009),
    pin("spectralon", 0, BD, 0.157056, 0.025, 1.09863, 0.009),
    pin("spectralon", 0, DD, 0.325963, 0.024, 1.00382, 0.0013),
    pin("spectralon", 0, PBD, 0.076651, 0.021, 1.00382, 0.0013),
    pin("spectralon", 0, CB, 0.358665, 0.03, 1.00382, 0.0013),
    pin("spectralon", 1, SD, 0.079406, 0.017, 1.0806, 0.0072),
    pin("spectralon", 1, BD, 0.091831, 0.017, 1.0806, 0.0072),
    pin("spectralon", 1, DD, 0.279349, 0.019, 1.0024, 0.0011),
    pin("spectralon", 1, PBD, 0.044245, 0.015, 1.0024, 0.0011),
    pin("spectralon", 1, CB, 0.301756, 0.02, 1.0024, 0.0011),
    pin("spectralon", 2, SD, 0.126032, 0.02, 1.10193, 0.0093),
    pin("spectralon", 2, BD, 0.140287, 0.021, 1.10193, 0.0093),
    pin("spectralon", 2, DD, 0.301219, 0.021, 1.002, 0.00093),
    pin("spectralon", 2, PBD, 0.056257, 0.015, 1.002, 0.00093),
    pin("spectralon", 2, CB, 0.330147, 0.022, 1.002, 0.00093),
    pin("spectralon", 0, MCT, 0.031235, 0.01, 0.999668, 0.0012),
    pin("spectralon", 1, MCT, 0.032439, 0.0085, 0.99825, 0.0011),
    pin("spectralon", 2, MCT, 0.019156, 0.0082, 0.997856, 0.00093),
    // wholemilk
    pin("wholemilk", 0, SD, 0.194488, 0.025, 1.08883, 0.006),
    pin("wholemilk", 0, BD, 0.140323, 0.014, 1.094, 0.006),
    pin("wholemilk", 0, DD, 0.344754, 0.017, 1.09795, 0.004),
    pin("wholemilk", 0, PBD, 0.064912, 0.013, 1.04059, 0.0038),
    pin("wholemilk", 0, CB, 0.51818, 0.022, 1.04059, 0.0038),
    pin("wholemilk", 1, SD, 0.196105, 0.024, 1.0901, 0.0057),
    pin("wholemilk", 1, BD, 0.160255, 0.0059, 1.09624, 0.0058),
    pin("wholemilk", 1, DD, 0.347994, 0.015, 1.13112, 0.0046),
    pin("wholemilk", 1, PBD, 0.071559, 0.0087, 1.04293, 0.0043),
    pin("wholemilk", 1, CB, 0.504557, 0.021, 1.04293, 0.0043),
    pin("wholemilk", 2, SD, 0.242559, 0.022, 1.08044, 0.0098),
    pin("wholemilk", 2, BD, 0.165494, 0.024, 1.0864, 0.0098),
    pin("wholemilk", 2, DD, 0.381128, 0.026, 1.28492, 0.0084),
    pin("wholemilk", 2, PBD, 0.092217, 0.016, 1.03786, 0.0068),
    pin("wholemilk", 2, CB, 0.500191, 0.034, 1.03786, 0.0068),
    pin("wholemilk", 0, MCT, 0.019958, 0.0078, 1.00238, 0.0037),
    pin("wholemilk", 1, MCT, 0.031654, 0.0052, 1.00381, 0.0041),
    pin("wholemilk", 2, MCT, 0.062407, 0.014, 0.995259, 0.0065),
];

/// Photons per channel of a preset (see "Cost" in the module documentation).
fn photons(preset: &str) -> u64 {
    match preset {
        "marble" | "potato" => 65_536,
        "chicken1" | "chicken2" => 32_768,
        "apple" | "skimmilk" => 8192,
        "wholemilk" => 4096,
        "cream" => 2048,
        "spectralon" => 1024,
        _ => 131_072,
    }
}

/// The radial range of channel `ch`: the standard dipole's radius holding 99 % of its
/// reflectance, as `cargo xtask compare` uses.
fn r_max(medium: &Medium, ch: usize) -> f64 {
    make_model(SD, medium).radius_for_energy(ch, 0.99)
}

fn simulate_channel(
    medium: &Medium,
    ch: usize,
    photons: u64,
    seed: u64,
    bins: usize,
) -> WalkProfile {
    simulate(
        medium,
        &WalkConfig {
            photons,
            seed,
            r_max: r_max(medium, ch),
            bins,
            channels: std::array::from_fn(|c| c == ch),
            spacing: BinSpacing::Linear,
        },
    )
    .unwrap()
}

/// The model's area average of R_d over each bin of `mc`.
fn bin_averages(model: &dyn Bssrdf, ch: usize, mc: &WalkProfile) -> Vec<f64> {
    let scale = model.medium().reduced_mean_free_path(ch);
    mc.bin_edges
        .windows(2)
        .zip(mc.bin_areas())
        .map(|(e, a)| integrate_radial_range(&|r| model.rd(ch, r), scale, e[0], e[1]) / a)
        .collect()
}

/// The standard and better dipoles model multiple scattering only; the others all of it (see
/// the module documentation for the directional dipole).
fn models_everything(kind: ModelKind) -> bool {
    matches!(kind, PBD | CB | DD | MCT)
}

/// (relative L2 error of the energy per bin, model total / Monte Carlo total) of `kind`.
fn compare(medium: &Medium, kind: ModelKind, ch: usize, mc: &WalkProfile) -> (f64, f64) {
    let model = make_model(kind, medium);
    let (reference, total): (Vec<f64>, f64) = if models_everything(kind) {
        (mc.rd[ch].clone(), mc.total[ch])
    } else {
        (
            mc.rd[ch]
                .iter()
                .zip(&mc.rd_single[ch])
                .map(|(t, s)| (t - s).max(0.0))
                .collect(),
            mc.total[ch] - mc.total_single[ch],
        )
    };
    let avg = bin_averages(model.as_ref(), ch, mc);
    let (mut num, mut den) = (0.0, 0.0);
    for ((a, m), r) in mc.bin_areas().iter().zip(&avg).zip(&reference) {
        num += (a * (m - r)).powi(2);
        den += (a * r).powi(2);
    }
    assert!(den > 0.0, "{kind} ch{ch}: empty reference");
    (
        (num / den).sqrt(),
        model.total_diffuse_reflectance(ch) / total,
    )
}

/// Checks every pin of `preset`; reports all misses at once.
fn check_preset(preset: &str) {
    let medium = Medium::preset(preset).unwrap();
    let pins: Vec<&Pin> = PINS.iter().filter(|p| p.preset == preset).collect();
    assert_eq!(pins.len(), 18, "{preset}: one pin per channel and model");
    let mut failures = Vec::new();
    for ch in 0..3 {
        let mc = simulate_channel(&medium, ch, photons(preset), SEED, BINS);
        for kind in ModelKind::ALL {
            let p = pins.iter().find(|p| p.ch == ch && p.kind == kind).unwrap();
            let (err, ratio) = compare(&medium, kind, ch, &mc);
            let err_margin = 3.0 * p.err_sd + REL_ERR_SLACK * p.err;
            let ratio_margin = 3.0 * p.ratio_sd + REL_RATIO_SLACK * p.ratio;
            println!(
                "{preset} ch{ch} {kind}: L2 error {err:.6} (pinned {} ± {err_margin:.4}), \
                 total ratio {ratio:.6} (pinned {} ± {ratio_margin:.4})",
                p.err, p.ratio
            );
            if (err - p.err).abs() > err_margin {
                failures.push(format!(
                    "{preset} ch{ch} {kind}: relative L2 error {err:.6}, pinned {} ± {err_margin:.5} \
                     ({:+.1} %)",
                    p.err,
                    100.0 * (err / p.err - 1.0)
                ));
            }
            if (ratio - p.ratio).abs() > ratio_margin {
                failures.push(format!(
                    "{preset} ch{ch} {kind}: total / Monte Carlo total {ratio:.6}, pinned {} ± \
                     {ratio_margin:.5} ({:+.2} %)",
                    p.ratio,
                    100.0 * (ratio / p.ratio - 1.0)
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn skin1_errors_against_monte_carlo_are_pinned() {
    check_preset("skin1");
}

#[test]
fn marble_errors_against_monte_carlo_are_pinned() {
    check_preset("marble");
}

#[test]
fn ketchup_errors_against_monte_carlo_are_pinned() {
    check_preset("ketchup");
}

#[test]
fn skin2_errors_against_monte_carlo_are_pinned() {
    check_preset("skin2");
}

#[test]
fn potato_errors_against_monte_carlo_are_pinned() {
    check_preset("potato");
}

#[test]
fn apple_errors_against_monte_carlo_are_pinned() {
    check_preset("apple");
}

#[test]
fn chicken1_errors_against_monte_carlo_are_pinned() {
    check_preset("chicken1");
}

#[test]
fn chicken2_errors_against_monte_carlo_are_pinned() {
    check_preset("chicken2");
}

#[test]
fn cream_errors_against_monte_carlo_are_pinned() {
    check_preset("cream");
}

#[test]
fn skimmilk_errors_against_monte_carlo_are_pinned() {
    check_preset("skimmilk");
}

#[test]
fn spectralon_errors_against_monte_carlo_are_pinned() {
    check_preset("spectralon");
}

#[test]
fn wholemilk_errors_against_monte_carlo_are_pinned() {
    check_preset("wholemilk");
}

#[test]
fn every_preset_is_pinned() {
    // One pin per channel and model for each material of the table, no pin for anything else.
    for p in presets::PRESETS.iter() {
        let n = PINS.iter().filter(|q| q.preset == p.name).count();
        assert_eq!(n, 18, "{}: {n} pins", p.name);
    }
    assert_eq!(PINS.len(), 18 * presets::PRESETS.len());
}

/// Jensen et al. 2001, Eq. 7 (Egan & Hilgeman 1979): the internal diffuse Fresnel reflectance
/// F_dr = −1.440/η² + 0.710/η + 0.668 + 0.0636η, accurate to about 1 %.
fn f_dr_egan_hilgeman(eta: f64) -> f64 {
    -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta
}

/// Jensen et al. 2001's total diffuse reflectance of the dipole (the formula below their
/// Eq. 5): R_d = (α'/2)(1 + e^{−(4/3)A√(3(1−α'))}) e^{−√(3(1−α'))}, A = (1 + F_dr)/(1 − F_dr).
fn jensen_total(alpha_p: f64, f_dr: f64) -> f64 {
    let a = (1.0 + f_dr) / (1.0 - f_dr);
    let s = (3.0 * (1.0 - alpha_p)).sqrt();
    0.5 * alpha_p * (1.0 + (-(4.0 / 3.0) * a * s).exp()) * (-s).exp()
}

#[test]
fn standard_dipole_total_is_jensens_formula_with_the_papers_fresnel_fit() {
    // The paper's recipe, typed in: its R_d formula with its F_dr fit. Per value, the
    // tolerance is the change of R_d when F_dr moves by the fit's stated 1 % (the crate uses
    // the exact F_dr, 0.07 % from the fit at η = 1.3); z_v × 1.1 is worth a ~12 % change of A,
    // ten times that. Unit σ'_t, so α' = σ'_s.
    for eta in [1.3, 1.4, 1.5] {
        let fit = f_dr_egan_hilgeman(eta);
        for alpha_p in [0.01, 0.1, 0.3, 0.5, 0.7, 0.8, 0.9, 0.95, 0.99, 0.999] {
            let m = Medium::new([1.0 - alpha_p; 3], [alpha_p; 3], 0.0, eta).unwrap();
            let ours = make_model(SD, &m).total_diffuse_reflectance(0);
            let paper = jensen_total(alpha_p, fit);
            let tol = (jensen_total(alpha_p, fit * 1.01) - paper)
                .abs()
                .max((jensen_total(alpha_p, fit * 0.99) - paper).abs())
                + 1e-12;
            assert!(
                (ours - paper).abs() <= tol,
                "eta {eta} alpha' {alpha_p}: {ours} vs paper {paper} ± {tol:.2e}"
            );
            // With the exact F_dr (checked against the literature in fresnel_literature.rs)
            // the formula must hold to rounding: the model's A comes from its z_v.
            let exact = jensen_total(alpha_p, fresnel::diffuse_fresnel_reflectance(1.0 / eta));
            assert!(
                (ours - exact).abs() <= 1e-12 * exact.max(1e-300),
                "eta {eta} alpha' {alpha_p}: {ours} vs {exact}"
            );
        }
    }
}

#[test]
fn standard_dipole_profile_is_jensens_equation_5() {
    // Jensen et al. 2001 Eq. 5, typed in: R_d(r) = α'/(4π) [z_r(1 + σ_tr d_r)e^{−σ_tr d_r}/d_r³
    // + z_v(1 + σ_tr d_v)e^{−σ_tr d_v}/d_v³], z_r = 1/σ'_t, z_v = z_r(1 + 4A/3),
    // σ_tr = √(3σ_aσ'_t), A from the internal F_dr. Rounding-level agreement.
    for name in ["skin1", "marble", "ketchup"] {
        let m = Medium::preset(name).unwrap();
        let f_dr = fresnel::diffuse_fresnel_reflectance(1.0 / m.eta());
        let a = (1.0 + f_dr) / (1.0 - f_dr);
        let sd = make_model(SD, &m);
        for ch in 0..3 {
            let (sa, sp) = (m.sigma_a()[ch], m.sigma_s()[ch] * (1.0 - m.g()));
            let st = sa + sp;
            let (alpha_p, sigma_tr) = (sp / st, (3.0 * sa * st).sqrt());
            let z_r = 1.0 / st;
            let z_v = z_r * (1.0 + 4.0 * a / 3.0);
            let term = |z: f64, r: f64| {
                let d = (r * r + z * z).sqrt();
                z * (1.0 + sigma_tr * d) * (-sigma_tr * d).exp() / (d * d * d)
            };
            for k in [0.0, 0.1, 0.5, 1.0, 3.0, 10.0] {
                let r = k * z_r;
                let want = alpha_p / (4.0 * std::f64::consts::PI) * (term(z_r, r) + term(z_v, r));
                let got = sd.rd(ch, r);
                assert!(
                    (got - want).abs() <= 1e-12 * want,
                    "{name} ch{ch} r {r}: {got} vs {want}"
                );
            }
        }
    }
}

#[test]
fn monte_carlo_profile_scales_with_the_coefficients() {
    // Scaling σ_a and σ_s by k scales every length by 1/k: R_d(r) → k² R_d(k r), the total is
    // unchanged, and the first radial moment ∫ r · 2πr R_d dr scales by 1/k. The scaled run
    // uses r_max/k, so its bin b is the unscaled bin b shrunk by k: its area average must be
    // k² times the unscaled one. Independent seeds, so the check is statistical (standard
    // errors of both runs; the estimators' honesty is tested in the crate's unit tests).
    let k = 2.5;
    let base = Medium::new([0.1; 3], [0.9; 3], 0.5, 1.3).unwrap();
    let scaled = Medium::new([0.1 * k; 3], [0.9 * k; 3], 0.5, 1.3).unwrap();
    let r_max = r_max(&base, 0);
    let bins = 16;
    let run = |m: &Medium, r_max: f64, seed: u64| {
        simulate(
            m,
            &WalkConfig {
                photons: 65_536,
                seed,
                r_max,
                bins,
                channels: [true, false, false],
                spacing: BinSpacing::Linear,
            },
        )
        .unwrap()
    };
    let a = run(&base, r_max, 21);
    let b = run(&scaled, r_max / k, 22);
    let k2 = k * k;
    let mut chi2 = 0.0;
    for i in 0..bins {
        let (want, want_se) = (k2 * a.rd[0][i], k2 * a.se[0][i]);
        let (got, got_se) = (b.rd[0][i], b.se[0][i]);
        let se = want_se.hypot(got_se);
        assert!(se > 0.0, "bin {i}");
        let z = (got - want) / se;
        chi2 += z * z;
        assert!(
            z.abs() < 4.5,
            "bin {i}: scaled {got} ± {got_se} vs k² × {want} ± {want_se}"
        );
    }
    // 16 bins: χ² has mean 16 and standard deviation √32.
    assert!(chi2 < 16.0 + 4.0 * 32f64.sqrt(), "chi2 {chi2}");
    let se = a.total_se[0].hypot(b.total_se[0]);
    assert!(
        (a.total[0] - b.total[0]).abs() < 4.0 * se,
        "totals {} vs {} ± {se}",
        a.total[0],
        b.total[0]
    );
    // First radial moment inside r_max by bin centres (the same quadrature for both runs, so
    // it scales exactly like the profile); its standard error treats the bins as independent.
    let moment = |p: &WalkProfile| {
        let (mut m, mut var) = (0.0, 0.0);
        for ((c, area), (v, s)) in p
            .bin_centers()
            .iter()
            .zip(p.bin_areas())
            .zip(p.rd[0].iter().zip(&p.se[0]))
        {
            m += c * v * area;
            var += (c * s * area).powi(2);
        }
        (m, var.sqrt())
    };
    let ((ma, sa), (mb, sb)) = (moment(&a), moment(&b));
    let se = sa.hypot(k * sb);
    assert!(
        (ma - k * mb).abs() < 4.0 * se,
        "first moments: {ma} vs k × {mb} = {} ± {se}",
        k * mb
    );
}

/// Mean exit radius inside r_max of binned profile values (bin centres, energy weights).
fn mean_radius(centers: &[f64], areas: &[f64], rd: &[f64]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for ((c, a), v) in centers.iter().zip(areas).zip(rd) {
        num += c * a * v;
        den += a * v;
    }
    num / den
}

#[test]
fn monte_carlo_mean_exit_radius_matches_photon_beam_diffusion() {
    // The length scale of the Monte Carlo walk against an independent computation: photon beam
    // diffusion (a different algorithm: diffusion of a beam plus single scattering, Habel et
    // al. 2013) predicts the mean exit radius of the full tally. Both are taken inside the same
    // r_max with the same bins (the model through its area averages), so truncation and
    // binning cancel. Measured today (seed 7, 65 536 photons): MC / PBD = 1.0136, 0.9949,
    // 0.9531, 1.0219, 0.9999, 0.9664, 1.0303 for the cases below in order; the seed-to-seed
    // standard deviation of the Monte Carlo mean radius is 0.3-0.8 %. The tolerance,
    // [`MEAN_RADIUS_TOLERANCE`], is the largest deviation (skin1 blue, 4.7 %) plus ~2.5 σ.
    // A walk whose steps are 10 % short shrinks every Monte Carlo radius by ~7.5 % inside
    // r_max (9 % without truncation), which takes skin1 green and skin2 blue beyond it.
    let cases = [
        ("skin1", 0),
        ("skin1", 1),
        ("skin1", 2),
        ("skin2", 0),
        ("skin2", 2),
        ("ketchup", 0),
        ("marble", 2),
    ];
    for (name, ch) in cases {
        let m = Medium::preset(name).unwrap();
        let mc = simulate_channel(&m, ch, 65_536, 7, BINS);
        let pbd = make_model(PBD, &m);
        let (centers, areas) = (mc.bin_centers(), mc.bin_areas());
        let ours = mean_radius(&centers, &areas, &mc.rd[ch]);
        let theirs = mean_radius(&centers, &areas, &bin_averages(pbd.as_ref(), ch, &mc));
        println!(
            "{name} ch{ch}: mean exit radius MC {ours:.5} mm, PBD {theirs:.5} mm, ratio {:.5}",
            ours / theirs
        );
        assert!(
            (ours / theirs - 1.0).abs() <= MEAN_RADIUS_TOLERANCE,
            "{name} ch{ch}: Monte Carlo mean exit radius {ours} mm vs photon beam diffusion {theirs} mm"
        );
    }
}

/// Largest accepted |MC / PBD − 1| of the mean exit radius (see the test above).
const MEAN_RADIUS_TOLERANCE: f64 = 0.065;
