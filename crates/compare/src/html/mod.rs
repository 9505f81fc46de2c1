//! `report.html`: the run's results as one self-contained page (no network, no external
//! script; every picture inlined as a data URI), written beside `report.md` by every run, each
//! experiment, `--quick` and a merge of shards alike. It is built from the output directory
//! alone (`report.md`, `results.csv`, `scenes/<scene>/*.png`), so an unsharded run and a merge
//! write the same page. Per scene: the reference and every method's image at the scene's one
//! exposure, over each other with a slider or side by side; crops of the hardest region
//! (where the methods' pictures differ most from the reference), zoomable; each method's
//! signed error and HDR-FLIP maps; its figures under the image and in a table; the error and
//! FLIP against run time as SVG charts whose points name their run on hover. Then report.md
//! as HTML, its tables and plots included.
//!
//! The page checks itself as it loads: `<body>` gets `data-ready`, `data-images` (how many
//! pictures), `data-broken` (how many failed to decode), `data-charts`, `data-points` and
//! `data-errors` (script errors), which the browser test (`tests/browser/`) reads.

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

/// Writes `out/report.html` from `report` (the text of `report.md`) and the files under `out`.
pub fn write(out: &Path, report: &str) -> Result<(), Error> {
    let viewers = scenes::viewers(out)?;
    let mut image = |file: &str| {
        // Only files inside the output directory (the report's own).
        let rel = Path::new(file);
        if rel.is_absolute() || rel.components().any(|c| c.as_os_str() == "..") {
            return None;
        }
        data_uri(&out.join(rel))
    };
    let body = markdown::to_html(report, &mut image);
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
}
