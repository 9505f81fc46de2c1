//! Writing outputs: atomic file writes and number formatting for the report.

use super::Error;
use std::path::Path;

/// Writes `bytes` to a temporary file next to `path` and renames it into place, so a reader
/// never sees a half-written file (`sss_util::write_atomic`).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    sss_util::write_atomic(path, bytes)
        .map_err(|e| Error(format!("cannot write '{}': {e}", path.display())))
}

/// A number for the CSV: shortest round-trip notation; empty for a missing or non-finite
/// value (never `NaN`/`inf`).
pub fn csv_num(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{x:e}"),
        _ => String::new(),
    }
}

/// A number for a Markdown table with `sig` significant digits; `–` when missing.
pub fn md_num(v: Option<f64>, sig: usize) -> String {
    match v {
        Some(x) if x.is_finite() => {
            if x == 0.0 {
                return "0".into();
            }
            let mag = x.abs().log10().floor() as i32;
            if (-3..5).contains(&mag) {
                let decimals = (sig as i32 - 1 - mag).max(0) as usize;
                format!("{x:.decimals$}")
            } else {
                format!("{x:.prec$e}", prec = sig.saturating_sub(1))
            }
        }
        _ => "–".into(),
    }
}

/// A percentage with 3 significant digits (`12.3 %`); `–` when missing.
pub fn md_pct(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() => format!("{} %", md_num(Some(100.0 * x), 3)),
        _ => "–".into(),
    }
}

/// A Markdown table from a header and rows.
pub fn md_table(header: &[&str], rows: &[Vec<String>]) -> String {
    let mut s = String::new();
    s.push_str(&format!("| {} |\n", header.join(" | ")));
    s.push_str(&format!(
        "|{}\n",
        header.iter().map(|_| "---|").collect::<String>()
    ));
    for r in rows {
        s.push_str(&format!("| {} |\n", r.join(" | ")));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers() {
        assert_eq!(csv_num(Some(0.25)), "2.5e-1");
        assert_eq!(csv_num(Some(f64::NAN)), "");
        assert_eq!(csv_num(None), "");
        assert_eq!(md_num(Some(0.012345), 3), "0.0123");
        assert_eq!(md_num(Some(123.456), 3), "123");
        assert_eq!(md_num(Some(1.5e-7), 3), "1.50e-7");
        assert_eq!(md_num(None, 3), "–");
        assert_eq!(md_pct(Some(0.1234)), "12.3 %");
    }

    #[test]
    fn atomic_write_replaces() {
        let dir = std::env::temp_dir().join(format!("xtask-out-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.txt");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        assert!(write_atomic(&dir.join("no/such/dir.txt"), b"x").is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
