//! Radial profiles R_d(r) of a model or of the Monte Carlo reference, evaluated into rows: what
//! `sss profile` prints and the Python `Model.profile` returns.
//!
//! [`ProfileRequest`] says what to compute (a [`ProfileModel`], a [`MediumSpec`], the radii or
//! bins), [`compute`] evaluates it into [`ProfileRows`], which writes itself as CSV
//! ([`ProfileRows::write_csv`]). [`check_budget`] refuses a request whose rows would not fit
//! in memory before anything is allocated.
//!
//! ```
//! use sss_bssrdf::MediumSpec;
//! use sss_bssrdf::profile_rows::{compute, ProfileModel, ProfileRequest};
//! let req = ProfileRequest {
//!     steps: 4,
//!     ..ProfileRequest::new(ProfileModel::Pbd, MediumSpec::Preset("skin1".into()), 5.0)
//! };
//! let rows = compute(&req, &|_| {})?;
//! let mut csv = Vec::new();
//! rows.write_csv(&mut csv).unwrap();
//! assert!(String::from_utf8(csv).unwrap().starts_with("# total_diffuse_reflectance="));
//! # Ok::<(), sss_bssrdf::BssrdfError>(())
//! ```

use crate::monte_carlo::{self, BinSpacing, WalkConfig};
use crate::{BssrdfError, MediumSpec, ModelKind, Rgb, make_model};
use std::io::Write;

/// Largest accepted `steps` (rows) for an analytic model, to keep the output bounded.
pub const MAX_STEPS: usize = 10_000_000;

/// What produces the profile: one of the models, or the Monte Carlo reference.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ProfileModel {
    /// Jensen et al. 2001.
    StandardDipole,
    /// d'Eon 2012.
    BetterDipole,
    /// Frisvad et al. 2014 (its normal-incidence radial profile).
    DirectionalDipole,
    /// Photon beam diffusion (Habel et al. 2013), tabulated as in pbrt.
    Pbd,
    /// Christensen-Burley normalized diffusion (Christensen & Burley 2015).
    Burley,
    /// The crate's photon random walk, tabulated (η in [1, 1.5]).
    McTable,
    /// The Monte Carlo photon random walk of `sss_bssrdf::monte_carlo`.
    MonteCarlo,
}

impl ProfileModel {
    /// Every variant, in the order `sss profile --help` lists them.
    pub const ALL: [ProfileModel; 7] = [
        ProfileModel::StandardDipole,
        ProfileModel::BetterDipole,
        ProfileModel::DirectionalDipole,
        ProfileModel::Pbd,
        ProfileModel::Burley,
        ProfileModel::McTable,
        ProfileModel::MonteCarlo,
    ];

    /// The analytic model, or `None` for the Monte Carlo reference.
    pub fn kind(self) -> Option<ModelKind> {
        match self {
            ProfileModel::StandardDipole => Some(ModelKind::StandardDipole),
            ProfileModel::BetterDipole => Some(ModelKind::BetterDipole),
            ProfileModel::DirectionalDipole => Some(ModelKind::DirectionalDipole),
            ProfileModel::Pbd => Some(ModelKind::PhotonBeamDiffusion),
            ProfileModel::Burley => Some(ModelKind::Burley),
            ProfileModel::McTable => Some(ModelKind::McTable),
            ProfileModel::MonteCarlo => None,
        }
    }

    /// The command-line name (the same as [`ModelKind::name`] for the models).
    pub fn name(self) -> &'static str {
        match self.kind() {
            Some(k) => k.name(),
            None => "monte-carlo",
        }
    }
}

impl std::fmt::Display for ProfileModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for ProfileModel {
    type Err = BssrdfError;

    /// A model by its command-line name ([`ProfileModel::name`]).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        ProfileModel::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = ProfileModel::ALL.iter().map(|m| m.name()).collect();
                BssrdfError::InvalidArgument(format!(
                    "unknown profile model '{s}' (one of: {})",
                    names.join(", ")
                ))
            })
    }
}

/// Everything `sss profile` needs.
#[derive(Clone, Debug, PartialEq)]
pub struct ProfileRequest {
    /// The model (or Monte Carlo).
    pub model: ProfileModel,
    /// The medium.
    pub medium: MediumSpec,
    /// Relative index of refraction; `None` keeps the default 1.3 (the presets' value).
    pub eta: Option<f64>,
    /// Largest radius (mm).
    pub r_max: f64,
    /// Number of rows: radii for a model, radial bins for Monte Carlo.
    pub steps: usize,
    /// Log-spaced radii from r_max·1e-4 to r_max instead of linear r_max/N..r_max (models only).
    pub log: bool,
    /// Monte Carlo photons per channel.
    pub photons: u64,
    /// Monte Carlo seed.
    pub seed: u64,
}

impl ProfileRequest {
    /// A request with the command-line defaults: 100 linear steps, 10⁶ photons, seed 1.
    pub fn new(model: ProfileModel, medium: MediumSpec, r_max: f64) -> Self {
        ProfileRequest {
            model,
            medium,
            eta: None,
            r_max,
            steps: 100,
            log: false,
            photons: 1_000_000,
            seed: 1,
        }
    }
}

/// One row of a profile table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProfileRow {
    /// Radius (mm); the bin centre for Monte Carlo.
    pub r: f64,
    /// R_d per channel (1/mm²); the bin's area average for Monte Carlo.
    pub rd: Rgb,
    /// Standard error of `rd` (Monte Carlo only).
    pub se: Option<Rgb>,
}

/// A computed profile.
#[derive(Clone, Debug, PartialEq)]
pub struct ProfileRows {
    /// What produced it.
    pub model: ProfileModel,
    /// A short description of the medium (preset name or coefficients).
    pub medium_label: String,
    /// Total diffuse reflectance per channel (the model's, or Monte Carlo's estimate).
    pub total: Rgb,
    /// The rows, by increasing radius.
    pub rows: Vec<ProfileRow>,
}

/// The radii of a model profile: `steps` values r_max/N, 2r_max/N, …, r_max, or with `log`
/// log-spaced from r_max·1e-4 to r_max (a single step gives r_max).
pub fn radii(r_max: f64, steps: usize, log: bool) -> Vec<f64> {
    (0..steps)
        .map(|i| {
            if log {
                if steps == 1 {
                    r_max
                } else {
                    r_max * 10f64.powf(-4.0 + 4.0 * i as f64 / (steps - 1) as f64)
                }
            } else if i + 1 == steps {
                r_max
            } else {
                r_max * (i + 1) as f64 / steps as f64
            }
        })
        .collect()
}

/// Bytes of one CSV row at most: 7 numbers in shortest round-trip scientific notation (at most
/// 24 characters each, e.g. `-1.2345678901234567e-308`) and their separators.
const CSV_ROW_BYTES: u64 = 7 * 25;

/// The estimated peak bytes of evaluating and printing `req` (saturating): per row the radius,
/// the [`ProfileRow`], the CSV text and a plot point per channel; for Monte Carlo also the
/// simulation's bin arrays ([`monte_carlo::memory_bytes`] on the current rayon threads). The
/// photon count costs time, not memory.
pub fn memory_bytes(req: &ProfileRequest) -> u64 {
    let per_row = (std::mem::size_of::<f64>() + std::mem::size_of::<ProfileRow>()) as u64
        + CSV_ROW_BYTES
        + 3 * 2 * std::mem::size_of::<f64>() as u64;
    let rows = (req.steps as u64).saturating_mul(per_row);
    match req.model {
        ProfileModel::MonteCarlo => rows.saturating_add(monte_carlo::memory_bytes(
            req.steps,
            rayon::current_num_threads(),
        )),
        _ => rows,
    }
}

/// Fails, naming `--steps`, the bytes needed and the budget, when `req` is estimated
/// ([`memory_bytes`]) to need more than `budget` bytes. Nothing is allocated before.
pub fn check_budget(req: &ProfileRequest, budget: u64) -> Result<(), BssrdfError> {
    let needed = memory_bytes(req);
    if needed > budget {
        return Err(BssrdfError::InvalidArgument(format!(
            "--steps {} ({}) needs about {needed} bytes ({}), over the memory budget of \
             {budget} bytes ({}); lower --steps or raise --max-memory",
            req.steps,
            if req.model == ProfileModel::MonteCarlo {
                "Monte Carlo bins"
            } else {
                "rows"
            },
            sss_util::human_bytes(needed),
            sss_util::human_bytes(budget)
        )));
    }
    Ok(())
}

fn check_request(req: &ProfileRequest) -> Result<(), BssrdfError> {
    if !(req.r_max.is_finite() && req.r_max > 0.0) {
        return Err(BssrdfError::InvalidArgument(format!(
            "--r-max {} must be a finite number of mm > 0",
            req.r_max
        )));
    }
    if req.steps == 0 {
        return Err(BssrdfError::InvalidArgument(
            "--steps must be at least 1".into(),
        ));
    }
    match req.model {
        ProfileModel::MonteCarlo => {
            if req.log {
                return Err(BssrdfError::InvalidArgument(
                    "--log is not available for --model monte-carlo (its bins are linear over [0, r_max])"
                        .into(),
                ));
            }
            if req.steps > monte_carlo::MAX_BINS {
                return Err(BssrdfError::InvalidArgument(format!(
                    "--steps {} exceeds the Monte Carlo limit of {} bins",
                    req.steps,
                    monte_carlo::MAX_BINS
                )));
            }
            if req.photons == 0 {
                return Err(BssrdfError::InvalidArgument(
                    "--photons must be at least 1".into(),
                ));
            }
        }
        _ => {
            if req.steps > MAX_STEPS {
                return Err(BssrdfError::InvalidArgument(format!(
                    "--steps {} exceeds the limit of {MAX_STEPS}",
                    req.steps
                )));
            }
        }
    }
    Ok(())
}

fn finite(what: &str, v: f64) -> Result<f64, BssrdfError> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(BssrdfError::NonFinite(format!(
            "{what} is {v}, not a finite number (a bug in the model; nothing was printed)"
        )))
    }
}

/// Evaluates `req`. `progress` receives the cumulative number of Monte Carlo photons
/// finished (over the three channels, so it ends at 3 × photons); it is not called for the
/// analytic models.
pub fn compute(
    req: &ProfileRequest,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<ProfileRows, BssrdfError> {
    check_request(req)?;
    let medium = req.medium.medium(req.eta)?;
    let medium_label = req.medium.label(&medium);
    if req.model == ProfileModel::McTable && !crate::mc_table::eta_in_range(medium.eta()) {
        return Err(BssrdfError::InvalidArgument(format!(
            "--eta {} is outside the range of the mc-table tables (η from {} to {}); use \
             another model for this medium",
            medium.eta(),
            crate::mc_table::ETAS[0],
            crate::mc_table::ETAS[crate::mc_table::ETAS.len() - 1]
        )));
    }
    let (total, rows) = match req.model.kind() {
        Some(kind) => {
            let model = make_model(kind, &medium);
            let mut total = [0.0; 3];
            for (ch, t) in total.iter_mut().enumerate() {
                *t = finite(
                    &format!("{kind} total diffuse reflectance [{ch}]"),
                    model.total_diffuse_reflectance(ch),
                )?;
            }
            let rows = radii(req.r_max, req.steps, req.log)
                .into_iter()
                .map(|r| {
                    let rd = model.rd_rgb(r);
                    for (ch, v) in rd.iter().enumerate() {
                        finite(&format!("{kind} Rd[{ch}]({r} mm)"), *v)?;
                    }
                    Ok(ProfileRow { r, rd, se: None })
                })
                .collect::<Result<Vec<_>, BssrdfError>>()?;
            (total, rows)
        }
        None => {
            let cfg = WalkConfig {
                photons: req.photons,
                seed: req.seed,
                r_max: req.r_max,
                bins: req.steps,
                channels: [true; 3],
                spacing: BinSpacing::Linear,
            };
            let mc = monte_carlo::simulate_with_progress(&medium, &cfg, progress)?;
            let rows = mc
                .bin_centers()
                .into_iter()
                .enumerate()
                .map(|(i, r)| {
                    let rd = [mc.rd[0][i], mc.rd[1][i], mc.rd[2][i]];
                    let se = [mc.se[0][i], mc.se[1][i], mc.se[2][i]];
                    for ch in 0..3 {
                        finite("Monte Carlo Rd", rd[ch])?;
                        finite("Monte Carlo standard error", se[ch])?;
                    }
                    Ok(ProfileRow {
                        r,
                        rd,
                        se: Some(se),
                    })
                })
                .collect::<Result<Vec<_>, BssrdfError>>()?;
            for t in mc.total {
                finite("Monte Carlo total", t)?;
            }
            (mc.total, rows)
        }
    };
    Ok(ProfileRows {
        model: req.model,
        medium_label,
        total,
        rows,
    })
}

impl ProfileRows {
    /// True when the rows carry standard errors (Monte Carlo).
    pub fn has_se(&self) -> bool {
        self.rows.iter().any(|r| r.se.is_some())
    }

    /// Writes the table as CSV: one comment line `# total_diffuse_reflectance=R,G,B`, the
    /// header `r_mm,rd_r,rd_g,rd_b` (plus `,se_r,se_g,se_b` for Monte Carlo) and one row per
    /// radius. Numbers are in shortest round-trip scientific notation (`1.25e-3`).
    pub fn write_csv(&self, w: &mut dyn Write) -> std::io::Result<()> {
        let [t0, t1, t2] = self.total;
        writeln!(w, "# total_diffuse_reflectance={t0:e},{t1:e},{t2:e}")?;
        let se = self.has_se();
        if se {
            writeln!(w, "r_mm,rd_r,rd_g,rd_b,se_r,se_g,se_b")?;
        } else {
            writeln!(w, "r_mm,rd_r,rd_g,rd_b")?;
        }
        for row in &self.rows {
            let [a, b, c] = row.rd;
            write!(w, "{:e},{a:e},{b:e},{c:e}", row.r)?;
            if se {
                let [x, y, z] = row.se.unwrap_or([0.0; 3]);
                write!(w, ",{x:e},{y:e},{z:e}")?;
            }
            writeln!(w)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absurd_steps_are_refused_by_the_budget_before_any_allocation() {
        for model in [ProfileModel::Pbd, ProfileModel::MonteCarlo] {
            let req = ProfileRequest {
                steps: 1_000_000_000_000_000,
                ..ProfileRequest::new(model, MediumSpec::Preset("skin1".into()), 5.0)
            };
            // 10^15 rows of at least 4 f64 each is 3.2e16 bytes, over any budget up to 2^54.
            let budget = 1u64 << 54;
            assert!(memory_bytes(&req) >= 32 * req.steps as u64);
            let msg = check_budget(&req, budget).unwrap_err().to_string();
            assert!(msg.contains("--steps 1000000000000000"), "{msg}");
            assert!(msg.contains(&format!("budget of {budget} bytes")), "{msg}");
            assert!(
                msg.contains("needs about ") && msg.contains("--max-memory"),
                "{msg}"
            );
        }
    }

    #[test]
    fn budget_counts_rows_and_monte_carlo_bins() {
        let skin = || MediumSpec::Preset("skin1".into());
        // 10^4 rows hold at least 10^4 × 4 f64 (radius and R_d) = 320 kB and, with the CSV
        // text of ≥ 4 numbers of ≥ 5 characters each, less than 10 MB.
        let req = ProfileRequest {
            steps: 10_000,
            ..ProfileRequest::new(ProfileModel::Pbd, skin(), 5.0)
        };
        let b = memory_bytes(&req);
        assert!((320_000..10_000_000).contains(&b), "{b}");
        assert!(check_budget(&req, 10_000_000).is_ok());
        assert!(check_budget(&req, 320_000).is_err());
        // Monte Carlo also holds ≥ 3 channels × 3 arrays (sum, squares, single) of bins.
        let mc = ProfileRequest {
            model: ProfileModel::MonteCarlo,
            ..req
        };
        assert!(memory_bytes(&mc) >= b + 9 * 8 * 10_000);
        // Photons do not change the estimate: they are not stored.
        let many = ProfileRequest {
            photons: u64::MAX,
            ..mc.clone()
        };
        assert_eq!(memory_bytes(&many), memory_bytes(&mc));
    }

    #[test]
    fn radii_linear_and_log() {
        let r = radii(2.0, 4, false);
        assert_eq!(r, vec![0.5, 1.0, 1.5, 2.0]);
        let r = radii(10.0, 5, true);
        assert!((r[0] - 1e-3).abs() < 1e-15 && (r[4] - 10.0).abs() < 1e-12);
        assert!((r[2] - 0.1).abs() < 1e-14);
        assert_eq!(radii(3.0, 1, true), vec![3.0]);
        assert_eq!(radii(3.0, 1, false), vec![3.0]);
    }

    #[test]
    fn names_parse_back_and_cover_the_models() {
        for m in ProfileModel::ALL {
            assert_eq!(m.name().parse::<ProfileModel>().unwrap(), m);
            assert_eq!(m.to_string(), m.name());
        }
        for k in ModelKind::ALL {
            let m = ProfileModel::ALL.iter().find(|m| m.kind() == Some(k));
            assert_eq!(m.map(|m| m.name()), Some(k.name()));
        }
        assert_eq!(ProfileModel::MonteCarlo.kind(), None);
        let e = "nope".parse::<ProfileModel>().unwrap_err().to_string();
        assert!(e.contains("'nope'") && e.contains("monte-carlo"), "{e}");
    }

    #[test]
    fn bad_requests_are_rejected() {
        let base = ProfileRequest::new(
            ProfileModel::StandardDipole,
            MediumSpec::Preset("skin1".into()),
            1.0,
        );
        for bad in [
            ProfileRequest {
                r_max: 0.0,
                ..base.clone()
            },
            ProfileRequest {
                r_max: f64::NAN,
                ..base.clone()
            },
            ProfileRequest {
                steps: 0,
                ..base.clone()
            },
            ProfileRequest {
                medium: MediumSpec::Preset("nope".into()),
                ..base.clone()
            },
            ProfileRequest {
                eta: Some(-1.0),
                ..base.clone()
            },
            ProfileRequest {
                model: ProfileModel::MonteCarlo,
                log: true,
                ..base.clone()
            },
        ] {
            assert!(compute(&bad, &|_| {}).is_err(), "{bad:?}");
        }
    }

    #[test]
    fn csv_layout() {
        let t = ProfileRows {
            model: ProfileModel::MonteCarlo,
            medium_label: "x".into(),
            total: [0.5, 0.25, 0.125],
            rows: vec![ProfileRow {
                r: 0.5,
                rd: [1.0, 2.0, 3.0],
                se: Some([0.1, 0.2, 0.3]),
            }],
        };
        let mut out = Vec::new();
        t.write_csv(&mut out).unwrap();
        let s = String::from_utf8(out).unwrap();
        assert_eq!(
            s,
            "# total_diffuse_reflectance=5e-1,2.5e-1,1.25e-1\nr_mm,rd_r,rd_g,rd_b,se_r,se_g,se_b\n5e-1,1e0,2e0,3e0,1e-1,2e-1,3e-1\n"
        );
    }
}
