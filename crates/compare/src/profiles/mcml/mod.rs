//! Every model against MCML, an independent Monte Carlo code (part of the "profiles"
//! experiment).
//!
//! MCML (L. Wang, S. L. Jacques, L. Zheng, *MCML — Monte Carlo modeling of light transport in
//! multi-layered tissues*, Comput. Methods Programs Biomed. 47, 1995) was run for a few
//! semi-infinite media under a normally incident pencil beam; the shared folder
//! (`<workspace>/../shared/reference/mcml`, or `SSS_MCML_DIR`) holds per case the medium, the
//! radial bin width, MCML's total diffuse reflectance with its standard error (`cases.csv`)
//! and Rd_r per radial bin, the bin's area average, with its standard error (`<case>.csv`).
//! The comparison follows `crates/bssrdf/tests/integration/mcml.rs`, which holds `mc-table`
//! to it:
//!
//! - MCML counts its photons before the specular reflection at the boundary,
//!   R_sp = ((η − 1)/(η + 1))² (Wang, Jacques & Zheng 1995, Eq. 3.1), while the models' R_d is
//!   per unit power entering, so MCML's values are divided by 1 − R_sp.
//! - A model's value for a bin is its area average over the MCML annulus (Gauss–Legendre over
//!   the bin of 2πr R_d, divided by the area).
//! - MCML's per-bin standard errors come from 5 batches and are themselves uncertain, so each
//!   is replaced by one pooled over the 21 bins around it ([`Case::normalised_bins`]).
//! - A bin's excess is (|model − MCML| − 3 SE)/MCML; a bin counts only as far as the 5 bins
//!   around it (masses summed, variances added) are beyond it too ([`worst`]), since single
//!   MCML bins have heavy-tailed errors.
//!
//! The models are compared as they are: the standard and better dipoles model multiple
//! scattering only, while MCML (like the other models) has every scattering order.

mod bins;
mod cases;
mod comparison;
mod report;
#[cfg(test)]
mod tests;

use super::metrics::median;
use super::{ModelMethod, ProfileMethod};
use crate::output::{Csv, csv_num, csv_text, md_num, md_pct, md_table};
use crate::walk_reference::WalkPart;
use crate::{Error, Section};
use bins::*;
pub use cases::*;
use comparison::*;
use rayon::prelude::*;
use report::*;
use sss_bssrdf::quadrature::integrate;
use sss_bssrdf::{Bssrdf, Medium, ModelKind, make_model};
use std::f64::consts::PI;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The subsection's heading.
pub const TITLE: &str = "Against MCML (independent Monte Carlo)";

/// The file written next to `profiles.csv`.
pub const CSV_NAME: &str = "mcml.csv";

/// The near range, in reduced mean free paths.
pub const NEAR: (f64, f64) = (0.25, 10.0);
/// The far range (beyond [`NEAR`]), in reduced mean free paths.
pub const FAR_END: f64 = 16.0;
/// MCML standard errors a model may differ by before its difference counts.
pub const SE_ALLOWANCE: f64 = 3.0;
/// The margins of `crates/bssrdf/tests/integration/mcml.rs` for the near and far ranges; a bin
/// beyond its margin alone but within it over its 5 bins is counted as *forgiven*.
pub const MARGINS: (f64, f64) = (0.03, 0.10);
/// Bins on each side of a bin in the forgiving rule's neighbourhood (5 bins in all).
const NEIGHBOURS: usize = 2;
/// Bins on each side over which the standard error is pooled (21 bins in all).
const POOL_HALF: usize = 10;
/// Gauss–Legendre points per MCML bin.
const GAUSS_POINTS: usize = 6;

/// The MCML part of the profiles experiment: compares every model with the cases in `dir`,
/// writes `out/mcml.csv` and returns (summary line, body subsection). When the folder is
/// absent or unusable it says so in both, writes no `mcml.csv` and removes one left by an
/// earlier run. Errors only when an output cannot be written.
pub fn run(dir: &Path, out: &Path) -> Result<Section, Error> {
    let csv = out.join(CSV_NAME);
    let skip = |why: String| -> Result<Section, Error> {
        if csv.exists() {
            std::fs::remove_file(&csv)
                .map_err(|e| Error(format!("cannot remove stale '{}': {e}", csv.display())))?;
        }
        let line = format!(
            "The comparison with MCML was skipped: {why} (set `SSS_MCML_DIR` to the folder of \
             the MCML profiles)."
        );
        Ok(Section {
            title: TITLE.into(),
            summary: format!("{line}\n"),
            body: format!("### {TITLE}\n\n{line}\n"),
        })
    };
    let (cases, skipped) = match load(dir) {
        Reference::Absent(why) | Reference::Unusable(why) => return skip(why),
        Reference::Found { cases, skipped } => (cases, skipped),
    };
    if cases.is_empty() {
        return skip(format!(
            "no usable case in `{}` ({})",
            dir.display(),
            skipped.join("; ")
        ));
    }
    let rows = compare_all(&cases);
    results_csv(&rows).write(&csv)?;
    let (summary, body) = report(&rows, &cases, &skipped, dir);
    Ok(Section {
        title: TITLE.into(),
        summary,
        body,
    })
}
