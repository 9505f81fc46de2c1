//! The shared MCML folder: where it is, its cases (`cases.csv`) and their radial profiles
//! (`<case>.csv`), read without ever panicking.

use super::*;

/// The folder of the MCML profiles: `SSS_MCML_DIR` when set, else
/// `<workspace>/../shared/reference/mcml`.
pub fn reference_dir() -> PathBuf {
    dir_from(std::env::var_os("SSS_MCML_DIR"))
}

pub(super) fn dir_from(env: Option<std::ffi::OsString>) -> PathBuf {
    match env {
        Some(d) if !d.is_empty() => PathBuf::from(d),
        _ => crate::workspace_root().join("../shared/reference/mcml"),
    }
}

/// One MCML case: the medium, MCML's total and its profile.
#[derive(Clone, Debug)]
pub struct Case {
    /// Name (also the profile's file name without `.csv`).
    pub name: String,
    /// The medium (the same coefficients in all three channels; channel 0 is used).
    pub medium: Medium,
    /// Radial bin width (mm).
    pub dr: f64,
    /// MCML's total diffuse reflectance per incident photon (specular reflection excluded).
    pub total: f64,
    /// Its standard error.
    pub total_se: f64,
    /// (bin centre (mm), Rd_r (1/mm²), SE (1/mm²)) per incident photon; bins without a tally
    /// are absent.
    pub bins: Vec<(f64, f64, f64)>,
}

/// The shared folder, read.
#[derive(Debug)]
pub enum Reference {
    /// No folder (or no `cases.csv` in it): the comparison is skipped.
    Absent(String),
    /// `cases.csv` is there but unusable: the comparison is skipped.
    Unusable(String),
    /// The cases read, and a note per case that was skipped (naming its file and why).
    Found {
        /// The usable cases, in `cases.csv` order.
        cases: Vec<Case>,
        /// One line per skipped case.
        skipped: Vec<String>,
    },
}

/// Reads the cases of `dir`. Never panics: a malformed `cases.csv` makes the whole folder
/// [`Reference::Unusable`]; a malformed row or profile skips that case with a note.
pub fn load(dir: &Path) -> Reference {
    let path = dir.join("cases.csv");
    let text = match std::fs::read_to_string(&path) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Reference::Absent(format!("there is no `{}`", path.display()));
        }
        Err(e) => return Reference::Unusable(format!("cannot read `{}`: {e}", path.display())),
    };
    let mut lines = text.lines().enumerate();
    let Some((_, header)) = lines.next() else {
        return Reference::Unusable(format!("`{}` is empty", path.display()));
    };
    let header: Vec<&str> = header.split(',').map(str::trim).collect();
    let required = [
        "case",
        "sigma_a_per_mm",
        "sigma_s_per_mm",
        "g",
        "eta",
        "dr_mm",
        "total_diffuse_reflectance",
        "total_se",
    ];
    let mut cols = [0usize; 8];
    for (c, name) in cols.iter_mut().zip(required) {
        match header.iter().position(|h| *h == name) {
            Some(i) => *c = i,
            None => {
                return Reference::Unusable(format!("`{}` has no column `{name}`", path.display()));
            }
        }
    }
    let above = header.iter().position(|h| *h == "eta_above");
    let (mut cases, mut skipped) = (Vec::new(), Vec::new());
    for (i, line) in lines.filter(|(_, l)| !l.trim().is_empty()) {
        match parse_case(dir, line, &cols, above) {
            Ok(c) => cases.push(c),
            Err(e) => skipped.push(format!("`cases.csv` line {}: {e}; skipped", i + 1)),
        }
    }
    Reference::Found { cases, skipped }
}

pub(super) fn parse_case(
    dir: &Path,
    line: &str,
    cols: &[usize; 8],
    above: Option<usize>,
) -> Result<Case, String> {
    let f: Vec<&str> = line.split(',').map(str::trim).collect();
    let field = |c: usize| f.get(c).copied().ok_or("too few fields");
    let name = field(cols[0])?.to_string();
    let valid_name = !name.is_empty()
        && !name.starts_with('.')
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_.-".contains(c));
    if !valid_name {
        return Err(format!("case name `{name}` is not a plain file name"));
    }
    let num = |c: usize, what: &str| -> Result<f64, String> {
        let s = field(c)?;
        match s.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(format!("{name}: {what} `{s}` is not a finite number")),
        }
    };
    let (sigma_a, sigma_s, g, eta) = (
        num(cols[1], "sigma_a_per_mm")?,
        num(cols[2], "sigma_s_per_mm")?,
        num(cols[3], "g")?,
        num(cols[4], "eta")?,
    );
    let (dr, total, total_se) = (
        num(cols[5], "dr_mm")?,
        num(cols[6], "total_diffuse_reflectance")?,
        num(cols[7], "total_se")?,
    );
    if let Some(c) = above {
        let a = num(c, "eta_above")?;
        if a != 1.0 {
            return Err(format!(
                "{name}: eta_above {a} (the models assume a medium of index 1 above)"
            ));
        }
    }
    let medium =
        Medium::new([sigma_a; 3], [sigma_s; 3], g, eta).map_err(|e| format!("{name}: {e}"))?;
    if dr <= 0.0 {
        return Err(format!("{name}: dr_mm {dr} is not positive"));
    }
    if total <= 0.0 || total > 1.0 || total_se < 0.0 {
        return Err(format!(
            "{name}: total {total} ± {total_se} is not a reflectance in (0, 1] with SE ≥ 0"
        ));
    }
    let file = format!("{name}.csv");
    let bins = parse_profile(&dir.join(&file)).map_err(|e| format!("`{file}`: {e}"))?;
    Ok(Case {
        name,
        medium,
        dr,
        total,
        total_se,
        bins,
    })
}

/// `r_mm,rd_per_mm2,se_per_mm2` (columns found by name), radii increasing, values finite and
/// non-negative, at least one bin.
pub(super) fn parse_profile(path: &Path) -> Result<Vec<(f64, f64, f64)>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("cannot read ({e})"))?;
    let mut lines = text.lines().enumerate();
    let header: Vec<&str> = lines
        .next()
        .ok_or("empty")?
        .1
        .split(',')
        .map(str::trim)
        .collect();
    let col = |n: &str| {
        header
            .iter()
            .position(|h| *h == n)
            .ok_or(format!("no column `{n}`"))
    };
    let (cr, cv, cs) = (col("r_mm")?, col("rd_per_mm2")?, col("se_per_mm2")?);
    let mut bins: Vec<(f64, f64, f64)> = Vec::new();
    for (i, line) in lines.filter(|(_, l)| !l.trim().is_empty()) {
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let get = |c: usize| -> Result<f64, String> {
            let s = f.get(c).ok_or(format!("line {}: too few fields", i + 1))?;
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && *v >= 0.0)
                .ok_or(format!(
                    "line {}: `{s}` is not a finite non-negative number",
                    i + 1
                ))
        };
        let bin = (get(cr)?, get(cv)?, get(cs)?);
        if bins.last().is_some_and(|b| b.0 >= bin.0) {
            return Err(format!("line {}: radii must increase", i + 1));
        }
        bins.push(bin);
    }
    if bins.is_empty() {
        return Err("no bins".into());
    }
    Ok(bins)
}
