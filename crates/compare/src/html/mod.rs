//! `report.html`: the run's results as one self-contained page (no network, no external
//! script; every picture inlined as a data URI), written beside `report.md` by every run, each
//! experiment, `--quick` and a merge of shards alike. It is built from the output directory
//! alone (`report.md`, `results.csv`, `scenes/<scene>/*.png`), so an unsharded run and a merge
//! write the same page. Per scene: the reference and every method's image at the scene's one
//! exposure, over each other with a slider or side by side; crops of the hardest region
//! (where the methods' pictures differ most from the reference), zoomable; each method's
//! signed error and HDR-FLIP maps; its figures under the image and in a table; the error and
//! FLIP against run time as SVG charts whose points name their run on hover. Then report.md
//! as HTML, its tables and plots included, and every other plot at the top of the directory;
//! a PNG plot with an SVG beside it (`output::plot_with_hover`: every experiment's error
//! against time) is shown as that chart, its points labelled on hover.
//!
//! The page checks itself as it loads: `<body>` gets `data-ready`, `data-images` (how many
//! pictures), `data-broken` (how many failed to decode), `data-charts`, `data-points` and
//! `data-errors` (script errors), which the browser test (`tests/browser/`) reads.
//!
//! The truth experiment's cases get viewers too (`truth/<case>/`: the `volpath` reference and
//! each model's `exact` image with its signed difference; figures from `truth.csv`).

mod markdown;
mod page;
mod scenes;

use super::Error;
use super::output::write_atomic;
use std::path::Path;

/// Standard base64 (RFC 4648, with padding).
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            chunk.get(1).copied().unwrap_or(0),
            chunk.get(2).copied().unwrap_or(0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..4 {
            if k <= chunk.len() {
                out.push(ALPHABET[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// PNG bytes as a data URI.
pub fn data_uri_of_png(bytes: &[u8]) -> String {
    format!("data:image/png;base64,{}", base64(bytes))
}

/// The file at `path` as a data URI (PNG or SVG by its extension), or `None` where it cannot
/// be read or is of another kind.
pub fn data_uri(path: &Path) -> Option<String> {
    let mime = match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
        "png" => "image/png",
        "svg" => "image/svg+xml",
        _ => return None,
    };
    let bytes = std::fs::read(path).ok()?;
    Some(format!("data:{mime};base64,{}", base64(&bytes)))
}

/// The markup of the picture `path` (with `alt` text): the SVG chart beside a PNG plot inlined
/// where there is one (its points label themselves on hover), else the picture as a data
/// URI; `None` when neither can be read.
fn picture(path: &Path, alt: &str) -> Option<String> {
    let svg = path.with_extension("svg");
    if path.extension().is_some_and(|e| e == "png")
        && let Ok(text) = std::fs::read_to_string(&svg)
        && text.starts_with("<svg ")
    {
        return Some(text.replacen("<svg ", "<svg class=\"chart\" ", 1));
    }
    let src = data_uri(path)?;
    Some(format!(
        "<img src=\"{}\" alt=\"{}\" class=\"figure\">",
        sss_plot::escape_xml(&src),
        sss_plot::escape_xml(alt)
    ))
}

/// Writes `out/report.html` from `report` (the text of `report.md`) and the files under `out`:
/// the scenes' viewers, the report, then every plot at the top of `out` the report does not
/// show (the error-against-time plots of each experiment among them), except the scenes'
/// `error_vs_time_<scene>.png`, whose charts the viewers draw.
pub fn write(out: &Path, report: &str) -> Result<(), Error> {
    let mut viewers = scenes::viewers(out);
    viewers.extend(scenes::truth_viewers(out));
    let mut shown: Vec<String> = viewers
        .iter()
        .map(|v| format!("error_vs_time_{}.png", v.scene))
        .collect();
    let mut image = |file: &str, alt: &str| {
        // Only files inside the output directory (the report's own).
        let rel = Path::new(file);
        if rel.is_absolute() || rel.components().any(|c| c.as_os_str() == "..") {
            return None;
        }
        shown.push(file.to_string());
        picture(&out.join(rel), alt)
    };
    let mut body = markdown::to_html(report, &mut image);
    let rest: Vec<String> = scenes::file_names(out)
        .into_iter()
        .filter(|f| f.ends_with(".png") && !shown.contains(f))
        .collect();
    if !rest.is_empty() {
        body.push_str("<h2 id=\"every-plot\">Every other plot of this run</h2>\n");
        for f in &rest {
            if let Some(p) = picture(&out.join(f), f) {
                body.push_str(&format!(
                    "<figure>{p}<figcaption><code>{}</code></figcaption></figure>\n",
                    sss_plot::escape_xml(f)
                ));
            }
        }
    }
    let html = page::page(&viewers, &body);
    write_atomic(&out.join("report.html"), html.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_matches_rfc_4648_test_vectors() {
        // RFC 4648 §10.
        for (plain, coded) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(base64(plain.as_bytes()), coded);
        }
        assert_eq!(base64(&[0xff, 0xfe, 0xfd]), "//79");
    }

    /// The page of a directory with no scenes: the report's own plot once, the other plots in
    /// the gallery (the chart of a plot with an SVG beside it inlined, a plain PNG as a
    /// picture), and a path out of the directory refused.
    #[test]
    fn every_plot_of_the_directory_is_shown_once() {
        let dir = std::env::temp_dir().join(format!("sss-html-gallery-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let png = |name: &str| {
            sss_render::image::write_png_rgb8(&dir.join(name), 2, 1, &[255, 0, 0, 0, 0, 255])
                .unwrap()
        };
        png("in_report.png");
        png("with_chart.png");
        png("plain.png");
        std::fs::write(
            dir.join("with_chart.svg"),
            "<svg viewBox=\"0 0 1 1\"><circle/></svg>",
        )
        .unwrap();
        let report = "# R\n\n![ours](in_report.png)\n\n![outside](../x.png)\n";
        write(&dir, report).unwrap();
        let html = std::fs::read_to_string(dir.join("report.html")).unwrap();
        assert_eq!(html.matches("alt=\"ours\"").count(), 1);
        assert!(html.contains("<figcaption><code>plain.png</code>"));
        assert!(!html.contains("<code>in_report.png</code>"), "shown once");
        assert!(html.contains("<svg class=\"chart\" viewBox=\"0 0 1 1\"><circle/></svg>"));
        assert!(html.contains("[outside — ../x.png not found]"));
        // Two pictures, the report's and the plain one: the charted PNG is shown as its chart.
        assert_eq!(html.matches("<img ").count(), 2, "{html}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
