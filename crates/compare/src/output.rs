//! Writing outputs: atomic file writes, the one CSV writer every experiment's table goes
//! through, and number formatting for the report.

use super::Error;
use sss_plot::{LabelledSeries, Series, hover_svg, line_plot};
use std::fmt::Display;
use std::path::Path;

/// Draws `series` as the PNG `path` ([`sss_plot::line_plot`]) and, beside it with the
/// extension `.svg`, the same chart for `report.html`, each point naming its series and
/// coordinates on hover ([`sss_plot::hover_svg`]). For the plots of error against time.
pub fn plot_with_hover(
    path: &Path,
    title: &str,
    (x_label, y_label): (&str, &str),
    series: &[Series],
    (log_x, log_y): (bool, bool),
) -> Result<(), Error> {
    let name = path.display();
    line_plot(path, title, x_label, y_label, series, log_x, log_y)
        .map_err(|e| Error(format!("{name}: {e}")))?;
    let labelled: Vec<LabelledSeries> = series
        .iter()
        .map(|s| LabelledSeries {
            name: s.name.clone(),
            points: s
                .points
                .iter()
                .map(|&(x, y)| {
                    let label = format!(
                        "{}: {x_label} {}, {y_label} {}",
                        s.name,
                        md_num(Some(x), 4),
                        md_num(Some(y), 4)
                    );
                    (x, y, label)
                })
                .collect(),
            color: s.color,
        })
        .collect();
    let svg = hover_svg(title, x_label, y_label, &labelled, log_x, log_y);
    write_atomic(&path.with_extension("svg"), svg.as_bytes())
}

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

/// One CSV file being built: a header line, then rows of exactly as many fields, each line
/// ended by `\n`. Every experiment writes its CSV through this type, with numbers from
/// [`csv_num`] and text from [`csv_text`], so every file formats, cleans and ends its lines
/// the same way and none can have a row of the wrong width.
#[derive(Clone, Debug)]
pub struct Csv {
    columns: usize,
    text: String,
}

impl Csv {
    /// A file with these column names (written as given: names are the crate's own
    /// identifiers, never user text).
    pub fn new<S: AsRef<str>>(columns: impl IntoIterator<Item = S>) -> Self {
        let names: Vec<String> = columns
            .into_iter()
            .map(|c| c.as_ref().to_string())
            .collect();
        let mut text = names.join(",");
        text.push('\n');
        Csv {
            columns: names.len(),
            text,
        }
    }

    /// Appends one row. Its width must be the header's: a row of another width is a bug in
    /// the experiment that builds it, never a property of the input, so it panics.
    pub fn row(&mut self, fields: impl IntoIterator<Item = String>) {
        let fields: Vec<String> = fields.into_iter().collect();
        assert_eq!(
            fields.len(),
            self.columns,
            "a CSV row of {} fields under a header of {}",
            fields.len(),
            self.columns
        );
        self.text.push_str(&fields.join(","));
        self.text.push('\n');
    }

    /// Writes the file atomically ([`write_atomic`]).
    pub fn write(&self, path: &Path) -> Result<(), Error> {
        write_atomic(path, self.text.as_bytes())
    }
}

impl From<Csv> for String {
    /// The file's text.
    fn from(csv: Csv) -> String {
        csv.text
    }
}

/// The columns of `csv`'s header that `docs/compare.md` does not name (in backticks): every
/// experiment's tests keep its CSV documented with this.
#[cfg(test)]
pub fn undocumented(csv: &Csv) -> Vec<String> {
    let path = crate::workspace_root().join("docs/compare.md");
    let doc = std::fs::read_to_string(&path)
        .unwrap_or_else(|e| panic!("cannot read '{}': {e}", path.display()));
    csv.text
        .lines()
        .next()
        .unwrap_or("")
        .split(',')
        .filter(|c| !doc.contains(&format!("`{c}`")))
        .map(String::from)
        .collect()
}

/// `text` as one CSV (or TSV) field: commas, tabs and line breaks become spaces, and runs of
/// spaces one space, so a name from a scene file or a CPU's model string cannot split a row.
pub fn csv_text(text: impl Display) -> String {
    text.to_string()
        .replace([',', '\t', '\n', '\r'], " ")
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
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
    fn csv_rows_follow_the_header() {
        let mut csv = Csv::new(["name", "value"]);
        csv.row([csv_text("a, b\tc\n"), csv_num(Some(2.0))]);
        csv.row([csv_text(7), csv_num(None)]);
        assert_eq!(String::from(csv), "name,value\na b c,2e0\n7,\n");
        assert_eq!(csv_text("  Intel(R), 2.9GHz "), "Intel(R) 2.9GHz");
    }

    #[test]
    fn undocumented_columns_are_found() {
        let csv = Csv::new(["rmse", "no_such_column_anywhere"]);
        assert_eq!(undocumented(&csv), ["no_such_column_anywhere"]);
    }

    #[test]
    #[should_panic(expected = "a CSV row of 1 fields under a header of 2")]
    fn a_row_of_another_width_is_refused() {
        Csv::new(["name", "value"]).row([csv_text("a")]);
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
