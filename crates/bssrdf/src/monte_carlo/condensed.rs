//! Condensed Monte Carlo: one photon random walk tallied for a whole grid of single-scattering
//! albedos at once, in optical units (σ_t = 1).
//!
//! With σ_t fixed, the geometry of a walk — free paths, scattering directions, Fresnel
//! splitting at the boundary — does not depend on the albedo ρ: only the weight does, by a
//! factor ρ per collision (the implicit absorption of [`super`]). A photon that escapes after
//! n collisions with weight w in a medium of albedo ρ_max therefore escapes with weight
//! w (ρ/ρ_max)ⁿ in a medium of albedo ρ ≤ ρ_max. Tallying that for every ρ of a grid turns one
//! simulation into a whole table of albedos (the "condensed Monte Carlo" of Graaff, Koelink,
//! de Mul, Zijlstra, Dassel, Aarnoudse, *Condensed Monte Carlo simulations for the description
//! of light transport*, Applied Optics 32(4), 1993, who rescale one absorption-free run by
//! aⁿ). Here the walk is exactly the walk of [`super::simulate`] for the medium of albedo
//! ρ_max = the largest albedo of the grid, Russian roulette included (it is decided on the
//! ρ_max weight and multiplies every row's weight alike, so it stays unbiased for all of
//! them).
//!
//! Because every row is tallied from the same photons, the rows are strongly correlated: the
//! escaped weight Σ w (ρ/ρ_max)ⁿ of every photon is non-decreasing in ρ, so the tallied total
//! and every bin are non-decreasing in ρ exactly, not just on average.
//!
//! **Strata by collision count.** [`CondensedConfig::min_events`] and
//! [`CondensedConfig::max_events`] restrict the tally to weight escaping after a range of
//! collision counts (walks stop after `max_events`). The profile is the sum over n of what
//! escapes after n collisions, so simulations of disjoint ranges add up to the full profile
//! (their standard errors in quadrature): the early collisions, which make the profile near
//! the entry point, can then get many cheap short walks, and the long walks of albedos near 1
//! are only needed for the late part (stratified sampling; e.g. Rubinstein & Kroese,
//! *Simulation and the Monte Carlo Method*, 3rd ed., §5.5). With the full range 1..=10⁶ and
//! the same seed and stream, the ρ_max row is bit-identical to [`super::simulate`].
//!
//! The bins are given by their edges in optical radius (mean free paths 1/σ_t). Each bin
//! reports the escaped weight per photon that left through it, i.e. the integral
//! ∫ 2πr R_d(r) dr of the reflectance profile over the bin (per unit power entering the
//! medium, normal incidence, σ_t = 1), with its standard error over photons as in
//! [`super`] (per-photon sums, so Fresnel splitting is accounted for).

use super::{
    CHUNK_PHOTONS, MAX_BINS, MAX_SCATTERING_EVENTS, Walk, chunk_seed, standard_error, trace_photon,
};
use crate::BssrdfError;
use rand::SeedableRng;
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;

/// Largest accepted number of (albedo row, bin) cells of one condensed simulation.
pub const MAX_CELLS: usize = 1 << 20;

/// What to simulate: a grid of albedos in a medium of unit extinction. Plain data; checked by
/// [`simulate_albedos`].
#[derive(Clone, Debug, PartialEq)]
pub struct CondensedConfig {
    /// Photons (≥ 1).
    pub photons: u64,
    /// Master seed.
    pub seed: u64,
    /// Stream index mixed into the chunk seeds like the channel of [`super::simulate`]
    /// (independent simulations with one master seed use different streams).
    pub stream: usize,
    /// The single-scattering albedos of the rows, each in [0, 1] (at least one).
    pub albedos: Vec<f64>,
    /// Henyey-Greenstein anisotropy, |g| < 1.
    pub g: f64,
    /// Relative index of refraction of the boundary (medium over outside), finite and > 0.
    pub eta: f64,
    /// Bin edges in optical radius: at least two, the first 0, strictly increasing, finite.
    pub edges: Vec<f64>,
    /// Only weight escaping after at least this many collisions is tallied (≥ 1).
    pub min_events: u64,
    /// Walks stop at collision `max_events + 1` (≤ [`MAX_SCATTERING_EVENTS`]); weight still
    /// carried then is reported in [`CondensedProfile::capped_weight`].
    pub max_events: u64,
    /// Per row, a factor applied to the exit radius before it is binned (each finite and > 0),
    /// or empty for 1 on every row. Row i is then tallied at radius s_i r: with
    /// s_i = 1 − ρ_i g, the reduced extinction σ'_t of row i's medium (σ_t = 1), its bins are
    /// in reduced mean free paths — what lets the `mc-table` tables for g ≠ 0 share the rows
    /// and radii of g = 0 (see [`crate::mc_table`]). The geometry of the walk does not depend
    /// on the scale, so the rows still share their photons.
    pub radius_scales: Vec<f64>,
}

impl CondensedConfig {
    /// Checks the configuration; [`simulate_albedos`] calls it first.
    pub fn validate(&self) -> Result<(), BssrdfError> {
        let bad = |msg: String| Err(BssrdfError::InvalidArgument(msg));
        if self.photons == 0 {
            return bad("condensed Monte Carlo: photons must be at least 1".into());
        }
        if self.albedos.is_empty() || !self.albedos.iter().all(|a| (0.0..=1.0).contains(a)) {
            return bad(format!(
                "condensed Monte Carlo: albedos {:?} must be a non-empty list of values in [0, 1]",
                self.albedos
            ));
        }
        if !(self.g.abs() < 1.0) {
            return Err(BssrdfError::InvalidG(self.g));
        }
        if !(self.eta > 0.0 && self.eta.is_finite()) {
            return Err(BssrdfError::InvalidEta(self.eta));
        }
        let bins = self.edges.len().saturating_sub(1);
        let valid = (1..=MAX_BINS).contains(&bins)
            && self.edges[0] == 0.0
            && self.edges.iter().all(|e| e.is_finite())
            && self.edges.windows(2).all(|w| w[0] < w[1]);
        if !valid {
            return bad(format!(
                "condensed Monte Carlo: {} bin edges; they must be 2..={} strictly increasing \
                 finite values starting at 0",
                self.edges.len(),
                MAX_BINS + 1
            ));
        }
        if !(1 <= self.min_events
            && self.min_events <= self.max_events
            && self.max_events <= MAX_SCATTERING_EVENTS)
        {
            return bad(format!(
                "condensed Monte Carlo: collision range {}..={} must lie in 1..={MAX_SCATTERING_EVENTS}",
                self.min_events, self.max_events
            ));
        }
        let scales_ok = self.radius_scales.is_empty()
            || (self.radius_scales.len() == self.albedos.len()
                && self.radius_scales.iter().all(|s| *s > 0.0 && s.is_finite()));
        if !scales_ok {
            return bad(format!(
                "condensed Monte Carlo: {} radius scales for {} albedos; give none or one finite \
                 positive scale per albedo",
                self.radius_scales.len(),
                self.albedos.len()
            ));
        }
        if self.albedos.len().saturating_mul(bins) > MAX_CELLS {
            return bad(format!(
                "condensed Monte Carlo: {} albedos × {bins} bins exceed {MAX_CELLS} cells",
                self.albedos.len()
            ));
        }
        Ok(())
    }

    fn bins(&self) -> usize {
        self.edges.len() - 1
    }
}

/// The tallies of a condensed simulation. All values are finite. Arrays over (row, bin) are
/// row-major: entry `i * bins + b`.
#[derive(Clone, Debug, PartialEq)]
pub struct CondensedProfile {
    /// The bin edges (optical radius).
    pub edges: Vec<f64>,
    /// The albedos of the rows.
    pub albedos: Vec<f64>,
    /// Escaped weight per photon in each (row, bin): ∫ 2πr R_d(r) dr over the bin.
    pub mass: Vec<f64>,
    /// Standard error of each value of `mass`.
    pub mass_se: Vec<f64>,
    /// Total diffuse reflectance per row: all escaped weight per photon, including weight
    /// escaping beyond the last edge.
    pub total: Vec<f64>,
    /// Standard error of `total`.
    pub total_se: Vec<f64>,
    /// Photons simulated.
    pub photons: u64,
    /// Photons stopped at collision `max_events + 1`.
    pub capped: u64,
    /// Weight per photon still carried by the stopped photons, per row (not tallied).
    pub capped_weight: Vec<f64>,
}

impl CondensedProfile {
    /// Number of bins.
    pub fn bins(&self) -> usize {
        self.edges.len() - 1
    }

    /// The bin masses of row `i`.
    pub fn row_mass(&self, i: usize) -> &[f64] {
        let n = self.bins();
        &self.mass[i * n..(i + 1) * n]
    }

    /// The standard errors of the bin masses of row `i`.
    pub fn row_mass_se(&self, i: usize) -> &[f64] {
        let n = self.bins();
        &self.mass_se[i * n..(i + 1) * n]
    }
}

/// Sums over a set of photons.
struct Tally {
    sum: Vec<f64>,
    sum_sq: Vec<f64>,
    total: Vec<f64>,
    total_sq: Vec<f64>,
    capped: u64,
    capped_weight: Vec<f64>,
}

impl Tally {
    fn new(rows: usize, bins: usize) -> Self {
        Tally {
            sum: vec![0.0; rows * bins],
            sum_sq: vec![0.0; rows * bins],
            total: vec![0.0; rows],
            total_sq: vec![0.0; rows],
            capped: 0,
            capped_weight: vec![0.0; rows],
        }
    }

    fn add(&mut self, other: &Tally) {
        let pairs = [
            (&mut self.sum, &other.sum),
            (&mut self.sum_sq, &other.sum_sq),
            (&mut self.total, &other.total),
            (&mut self.total_sq, &other.total_sq),
            (&mut self.capped_weight, &other.capped_weight),
        ];
        for (a, b) in pairs {
            for (x, y) in a.iter_mut().zip(b) {
                *x += y;
            }
        }
        self.capped += other.capped;
    }
}

/// One photon's deposits per (bin, row) — bin-major, so one escape writes one contiguous
/// run — and per row, accumulated before they are squared.
struct Scratch {
    cell: Vec<f64>,
    total: Vec<f64>,
    touched: Vec<usize>,
    /// Per bin, whether it is in `touched`.
    is_touched: Vec<bool>,
    /// Per row, the escaped weight of one escape (reused buffer).
    weights: Vec<f64>,
}

/// Runs the condensed walk of `cfg` (see the module documentation).
pub fn simulate_albedos(cfg: &CondensedConfig) -> Result<CondensedProfile, BssrdfError> {
    cfg.validate()?;
    let rows = cfg.albedos.len();
    let bins = cfg.bins();
    let rho_max = cfg.albedos.iter().copied().fold(0.0, f64::max);
    // (ρ_i/ρ_max): the per-collision factor of row i relative to the walk's weight.
    let ratios: Vec<f64> = cfg
        .albedos
        .iter()
        .map(|&a| if rho_max > 0.0 { a / rho_max } else { 0.0 })
        .collect();
    // Scales of exactly 1 take the one-bin-per-escape path (the g = 0 tables).
    let scales: &[f64] = if cfg.radius_scales.iter().all(|&s| s == 1.0) {
        &[]
    } else {
        &cfg.radius_scales
    };
    let r_max = cfg.edges[bins];
    let walk = Walk {
        sigma_t: 1.0,
        albedo: rho_max,
        g: cfg.g,
        eta_out: 1.0 / cfg.eta,
        analog: false,
        max_events: cfg.max_events,
        inv_dr: bins as f64 / r_max,
        r_max,
        bins,
        edges: Some(&cfg.edges),
        sphere: None,
    };

    let n_chunks = cfg.photons.div_ceil(CHUNK_PHOTONS);
    let mut tally = Tally::new(rows, bins);
    let batch = 8 * rayon::current_num_threads().max(1) as u64;
    let mut start = 0_u64;
    while start < n_chunks {
        let end = start.saturating_add(batch).min(n_chunks);
        let results: Vec<Tally> = (start..end)
            .into_par_iter()
            .map(|k| {
                let n = CHUNK_PHOTONS.min(cfg.photons - k * CHUNK_PHOTONS);
                let seed = chunk_seed(cfg.seed, cfg.stream, k);
                run_chunk(&walk, &ratios, scales, cfg.min_events, n, seed)
            })
            .collect();
        for t in &results {
            tally.add(t);
        }
        start = end;
    }

    let n = cfg.photons as f64;
    let mass = tally.sum.iter().map(|s| s / n).collect();
    let mass_se = tally
        .sum
        .iter()
        .zip(&tally.sum_sq)
        .map(|(&s, &s2)| standard_error(s, s2, n))
        .collect();
    let total = tally.total.iter().map(|s| s / n).collect();
    let total_se = tally
        .total
        .iter()
        .zip(&tally.total_sq)
        .map(|(&s, &s2)| standard_error(s, s2, n))
        .collect();
    let capped_weight = tally.capped_weight.iter().map(|s| s / n).collect();
    Ok(CondensedProfile {
        edges: cfg.edges.clone(),
        albedos: cfg.albedos.clone(),
        mass,
        mass_se,
        total,
        total_se,
        photons: cfg.photons,
        capped: tally.capped,
        capped_weight,
    })
}

fn run_chunk(
    walk: &Walk,
    ratios: &[f64],
    scales: &[f64],
    min_events: u64,
    photons: u64,
    seed: u64,
) -> Tally {
    let rows = ratios.len();
    let bins = walk.bins;
    let mut rng = Pcg64Mcg::seed_from_u64(seed);
    let mut tally = Tally::new(rows, bins);
    let mut scratch = Scratch {
        cell: vec![0.0; rows * bins],
        total: vec![0.0; rows],
        touched: Vec::new(),
        is_touched: vec![false; bins],
        weights: vec![0.0; rows],
    };
    for _ in 0..photons {
        let traced = trace_photon(
            walk,
            crate::DVec3::NEG_Z,
            &mut rng,
            &mut |_, r, w, events| {
                if events < min_events {
                    return;
                }
                // Collisions are counted up to the cap (≤ 10⁶), which fits an i32.
                let n = events.min(i32::MAX as u64) as i32;
                for (x, &q) in scratch.weights.iter_mut().zip(ratios) {
                    *x = w * q.powi(n);
                }
                for (t, x) in scratch.total.iter_mut().zip(&scratch.weights) {
                    *t += x;
                }
                if scales.is_empty() {
                    if let Some(b) = walk.bin(r) {
                        if !scratch.is_touched[b] {
                            scratch.is_touched[b] = true;
                            scratch.touched.push(b);
                        }
                        let cell = &mut scratch.cell[b * rows..(b + 1) * rows];
                        for (c, x) in cell.iter_mut().zip(&scratch.weights) {
                            *c += x;
                        }
                    }
                } else {
                    for (i, (&s, x)) in scales.iter().zip(&scratch.weights).enumerate() {
                        if let Some(b) = walk.bin(s * r) {
                            if !scratch.is_touched[b] {
                                scratch.is_touched[b] = true;
                                scratch.touched.push(b);
                            }
                            scratch.cell[b * rows + i] += x;
                        }
                    }
                }
            },
        );
        if let Some(w) = traced {
            tally.capped += 1;
            let n = walk.max_events.min(i32::MAX as u64) as i32;
            for (c, &q) in tally.capped_weight.iter_mut().zip(ratios) {
                *c += w * q.powi(n);
            }
        }
        // Flush the photon: its per-cell sums and their squares.
        for &b in &scratch.touched {
            for i in 0..rows {
                let x = scratch.cell[b * rows + i];
                tally.sum[i * bins + b] += x;
                tally.sum_sq[i * bins + b] += x * x;
                scratch.cell[b * rows + i] = 0.0;
            }
            scratch.is_touched[b] = false;
        }
        scratch.touched.clear();
        for i in 0..rows {
            let x = scratch.total[i];
            tally.total[i] += x;
            tally.total_sq[i] += x * x;
            scratch.total[i] = 0.0;
        }
    }
    tally
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Medium;
    use crate::monte_carlo::{BinSpacing, WalkConfig, simulate};

    fn config(photons: u64, albedos: Vec<f64>, eta: f64) -> CondensedConfig {
        CondensedConfig {
            photons,
            seed: 7,
            stream: 0,
            albedos,
            g: 0.0,
            eta,
            edges: vec![0.0, 0.3, 1.0, 2.5, 6.0],
            min_events: 1,
            max_events: MAX_SCATTERING_EVENTS,
            radius_scales: Vec::new(),
        }
    }

    #[test]
    fn top_row_is_the_ordinary_walk() {
        // The ρ_max row runs exactly the walk of `simulate` for that albedo (same chunk seeds
        // through the stream = channel 0), so its totals are the same bits and its bins the
        // same sums (divided by the annulus area there).
        for eta in [1.0, 1.3] {
            let c = config(3 * CHUNK_PHOTONS + 17, vec![0.25, 0.5, 0.75], eta);
            let p = simulate_albedos(&c).unwrap();
            let m = Medium::from_extinction_albedo([1.0; 3], [0.75; 3], 0.0, eta).unwrap();
            assert_eq!(m.sigma_t(0), 1.0);
            assert_eq!(m.albedo(0), 0.75);
            let mc = simulate(
                &m,
                &WalkConfig {
                    photons: c.photons,
                    seed: c.seed,
                    r_max: 6.0,
                    bins: 4,
                    channels: [true, false, false],
                    spacing: BinSpacing::Edges(c.edges.clone()),
                },
            )
            .unwrap();
            assert_eq!(p.total[2].to_bits(), mc.total[0].to_bits());
            assert_eq!(p.total_se[2].to_bits(), mc.total_se[0].to_bits());
            for (b, area) in mc.bin_areas().iter().enumerate() {
                let want = mc.rd[0][b] * area;
                assert!((p.row_mass(2)[b] - want).abs() <= 1e-14 * want, "bin {b}");
            }
            // Lower rows carry (ρ/ρ_max)ⁿ ≤ 1 of every escape: less, never more.
            for b in 0..4 {
                assert!(p.row_mass(0)[b] < p.row_mass(1)[b]);
                assert!(p.row_mass(1)[b] < p.row_mass(2)[b]);
            }
        }
    }

    #[test]
    fn a_radius_scale_bins_the_row_at_the_scaled_radius() {
        // Row ρ_max with scale 1/2 against `simulate` with every edge doubled: r/2 ≥ e exactly
        // when r ≥ 2e (both exact in binary), so the same photons fall in the same bins. The
        // other row keeps scale 1 and its plain bins.
        let c = CondensedConfig {
            g: 0.6,
            radius_scales: vec![1.0, 0.5],
            ..config(2 * CHUNK_PHOTONS + 3, vec![0.5, 0.8], 1.3)
        };
        let p = simulate_albedos(&c).unwrap();
        let plain = simulate_albedos(&CondensedConfig {
            radius_scales: Vec::new(),
            ..c.clone()
        })
        .unwrap();
        assert_eq!(p.row_mass(0), plain.row_mass(0));
        assert_eq!(p.total, plain.total);
        assert_ne!(p.row_mass(1), plain.row_mass(1));
        let m = Medium::from_extinction_albedo([1.0; 3], [0.8; 3], 0.6, 1.3).unwrap();
        let doubled: Vec<f64> = c.edges.iter().map(|e| 2.0 * e).collect();
        let mc = simulate(
            &m,
            &WalkConfig {
                photons: c.photons,
                seed: c.seed,
                r_max: doubled[doubled.len() - 1],
                bins: 4,
                channels: [true, false, false],
                spacing: BinSpacing::Edges(doubled),
            },
        )
        .unwrap();
        for (b, area) in mc.bin_areas().iter().enumerate() {
            let want = mc.rd[0][b] * area;
            assert!(want > 0.0);
            assert!((p.row_mass(1)[b] - want).abs() <= 1e-14 * want, "bin {b}");
        }
        // One scale per albedo, each finite and positive.
        for bad in [
            vec![1.0],
            vec![1.0, 0.0],
            vec![1.0, f64::NAN],
            vec![1.0, -1.0],
        ] {
            let c = CondensedConfig {
                radius_scales: bad,
                ..c.clone()
            };
            assert!(simulate_albedos(&c).is_err(), "{:?}", c.radius_scales);
        }
    }

    #[test]
    fn lower_rows_agree_with_the_ordinary_walk_at_their_albedo() {
        // Row 0.5 of a walk at ρ_max = 0.95 (weights 0.5ⁿ/0.95ⁿ, roulette on the 0.95 weight)
        // against `simulate` at albedo 0.5 (implicit capture at 0.5): different estimators of
        // the same bins, within 4 joint standard errors.
        for eta in [1.0, 1.4] {
            let c = config(40_000, vec![0.5, 0.95], eta);
            let p = simulate_albedos(&c).unwrap();
            let m = Medium::from_extinction_albedo([1.0; 3], [0.5; 3], 0.0, eta).unwrap();
            let mc = simulate(
                &m,
                &WalkConfig {
                    photons: 40_000,
                    seed: 99,
                    r_max: 6.0,
                    bins: 4,
                    channels: [true, false, false],
                    spacing: BinSpacing::Edges(c.edges.clone()),
                },
            )
            .unwrap();
            for (b, area) in mc.bin_areas().iter().enumerate() {
                let (f, f_se) = (mc.rd[0][b] * area, mc.se[0][b] * area);
                let (t, t_se) = (p.row_mass(0)[b], p.row_mass_se(0)[b]);
                let z = (t - f) / (t_se.powi(2) + f_se.powi(2)).sqrt();
                assert!(
                    z.abs() < 4.0,
                    "eta {eta} bin {b}: {t} ± {t_se} vs {f} ± {f_se}"
                );
            }
            let z = (p.total[0] - mc.total[0])
                / (p.total_se[0].powi(2) + mc.total_se[0].powi(2)).sqrt();
            assert!(z.abs() < 4.0, "eta {eta} total: z {z}");
        }
    }

    #[test]
    fn bit_identical_for_any_thread_count() {
        let c = CondensedConfig {
            min_events: 3,
            max_events: 40,
            ..config(2 * CHUNK_PHOTONS + 5, vec![0.9, 0.99], 1.4)
        };
        let run = |threads| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| simulate_albedos(&c).unwrap())
        };
        assert_eq!(run(1), run(2));
        assert_ne!(
            run(1),
            simulate_albedos(&CondensedConfig { stream: 1, ..c }).unwrap()
        );
    }

    #[test]
    fn strata_add_up_to_the_full_walk() {
        // Escapes after 1..=8 collisions plus those after 9.. are all escapes: the sum of two
        // independent strata agrees with a full run within their standard errors.
        let albedos = vec![0.6, 0.95];
        let full = simulate_albedos(&config(60_000, albedos.clone(), 1.3)).unwrap();
        let early = simulate_albedos(&CondensedConfig {
            stream: 1,
            max_events: 8,
            ..config(60_000, albedos.clone(), 1.3)
        })
        .unwrap();
        let late = simulate_albedos(&CondensedConfig {
            stream: 2,
            min_events: 9,
            ..config(60_000, albedos, 1.3)
        })
        .unwrap();
        assert!(early.capped > 0 && early.capped_weight[1] > 0.0);
        for i in 0..2 {
            for b in 0..4 {
                let sum = early.row_mass(i)[b] + late.row_mass(i)[b];
                let se = (early.row_mass_se(i)[b].powi(2)
                    + late.row_mass_se(i)[b].powi(2)
                    + full.row_mass_se(i)[b].powi(2))
                .sqrt();
                let z = (sum - full.row_mass(i)[b]) / se;
                assert!(z.abs() < 4.0, "row {i} bin {b}: z {z}");
            }
            // The early stratum alone misses the late escapes.
            assert!(early.total[i] < full.total[i]);
        }
    }

    #[test]
    fn bad_configs_are_errors() {
        let good = config(10, vec![0.5], 1.3);
        assert!(simulate_albedos(&good).is_ok());
        let bad = [
            CondensedConfig {
                photons: 0,
                ..good.clone()
            },
            CondensedConfig {
                albedos: vec![],
                ..good.clone()
            },
            CondensedConfig {
                albedos: vec![1.5],
                ..good.clone()
            },
            CondensedConfig {
                albedos: vec![f64::NAN],
                ..good.clone()
            },
            CondensedConfig {
                g: 1.0,
                ..good.clone()
            },
            CondensedConfig {
                eta: 0.0,
                ..good.clone()
            },
            CondensedConfig {
                edges: vec![0.0],
                ..good.clone()
            },
            CondensedConfig {
                edges: vec![0.1, 1.0],
                ..good.clone()
            },
            CondensedConfig {
                edges: vec![0.0, 1.0, 1.0],
                ..good.clone()
            },
            CondensedConfig {
                min_events: 0,
                ..good.clone()
            },
            CondensedConfig {
                min_events: 5,
                max_events: 4,
                ..good.clone()
            },
            CondensedConfig {
                max_events: MAX_SCATTERING_EVENTS + 1,
                ..good.clone()
            },
        ];
        for c in bad {
            assert!(simulate_albedos(&c).is_err(), "{c:?}");
        }
        // An all-absorbing grid reflects nothing.
        let dark = simulate_albedos(&config(100, vec![0.0], 1.3)).unwrap();
        assert_eq!(dark.total, vec![0.0]);
    }
}
