//! The measured materials as a table: the library behind `sss presets`.

use sss_bssrdf::presets::{PRESET_ETA, PRESETS};
use std::fmt::Write as _;

fn rgb(v: [f64; 3]) -> String {
    format!("{},{},{}", v[0], v[1], v[2])
}

/// Every preset of Jensen et al. 2001 Table 2, one line each.
///
/// With `csv`, the header is
/// `name,sigma_s_reduced_r,sigma_s_reduced_g,sigma_s_reduced_b,sigma_a_r,sigma_a_g,sigma_a_b,eta,published_rd_r,published_rd_g,published_rd_b`;
/// otherwise an aligned table for reading, with RGB triples written `R,G,B`.
/// Coefficients are in 1/mm; `published_rd` is the total diffuse reflectance printed in the
/// paper.
pub fn presets_table(csv: bool) -> String {
    let mut out = String::new();
    if csv {
        out.push_str(
            "name,sigma_s_reduced_r,sigma_s_reduced_g,sigma_s_reduced_b,sigma_a_r,sigma_a_g,sigma_a_b,eta,published_rd_r,published_rd_g,published_rd_b\n",
        );
        for p in &PRESETS {
            let _ = writeln!(
                out,
                "{},{},{},{},{}",
                p.name,
                rgb(p.sigma_s_reduced),
                rgb(p.sigma_a),
                PRESET_ETA,
                rgb(p.published_rd)
            );
        }
        return out;
    }
    let header = [
        "name",
        "sigma_s' R,G,B (1/mm)",
        "sigma_a R,G,B (1/mm)",
        "eta",
        "published Rd R,G,B",
    ];
    let rows: Vec<[String; 5]> = PRESETS
        .iter()
        .map(|p| {
            [
                p.name.to_string(),
                rgb(p.sigma_s_reduced),
                rgb(p.sigma_a),
                PRESET_ETA.to_string(),
                rgb(p.published_rd),
            ]
        })
        .collect();
    let widths: Vec<usize> = (0..5)
        .map(|c| {
            rows.iter()
                .map(|r| r[c].chars().count())
                .chain(std::iter::once(header[c].chars().count()))
                .max()
                .unwrap_or(0)
        })
        .collect();
    let mut line = |cells: [&str; 5]| {
        let mut l = String::new();
        for (c, cell) in cells.iter().enumerate() {
            if c > 0 {
                l.push_str("  ");
            }
            let _ = write!(l, "{cell:<w$}", w = widths[c]);
        }
        out.push_str(l.trim_end());
        out.push('\n');
    };
    line(header);
    for r in &rows {
        line([&r[0], &r[1], &r[2], &r[3], &r[4]]);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn both_layouts_list_every_preset() {
        for csv in [false, true] {
            let t = presets_table(csv);
            assert_eq!(t.lines().count(), PRESETS.len() + 1);
            for p in &PRESETS {
                assert!(t.lines().any(|l| l.starts_with(p.name)), "{}", p.name);
            }
        }
        let csv = presets_table(true);
        assert!(csv.lines().all(|l| l.split(',').count() == 11));
    }
}
