//! False-colour error maps: per-pixel values drawn with a colour bar and a title, as PNG.

use crate::PlotError;
use plotters::prelude::*;
use std::path::Path;

/// The "inferno"-like colour of t in [0, 1] (piecewise linear through 6 anchors of matplotlib's
/// inferno map).
pub fn false_colour(t: f64) -> [u8; 3] {
    const ANCHORS: [[f64; 3]; 6] = [
        [0.0, 0.0, 4.0],
        [66.0, 10.0, 104.0],
        [147.0, 38.0, 103.0],
        [221.0, 81.0, 58.0],
        [252.0, 165.0, 10.0],
        [252.0, 255.0, 164.0],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * 5.0;
    let i = (x.floor() as usize).min(4);
    let f = x - i as f64;
    let mut c = [0u8; 3];
    for k in 0..3 {
        c[k] = (ANCHORS[i][k] * (1.0 - f) + ANCHORS[i + 1][k] * f).round() as u8;
    }
    c
}

/// Draws a false-colour map of per-pixel `values` (None: not part of the comparison, drawn
/// grey) scaled from 0 to `max`, with a colour bar labelled `label` and a title, as a PNG.
pub fn write_error_map(
    path: &Path,
    width: u32,
    height: u32,
    values: &[Option<f64>],
    max: f64,
    title: &str,
    label: &str,
) -> Result<(), PlotError> {
    let draw_err = |message: String| PlotError::Draw {
        path: path.to_path_buf(),
        message,
    };
    if values.len() != width as usize * height as usize {
        return Err(draw_err(format!(
            "{} values for a {width}x{height} image",
            values.len()
        )));
    }
    crate::check_writable(path)?;
    let max = if max.is_finite() && max > 0.0 {
        max
    } else {
        1.0
    };
    let scale = (512 / width.max(height)).clamp(1, 8);
    let (iw, ih) = (width * scale, height * scale);
    let (bar_w, margin, title_h) = (150u32, 10u32, 30u32);
    let size = (iw + bar_w + 2 * margin, ih.max(200) + title_h + 2 * margin);
    crate::ensure_font()?;
    let draw = |tmp: &Path| -> Result<(), String> {
        let root = BitMapBackend::new(tmp, size).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        root.draw_text(
            title,
            &("sans-serif", 18).into_text_style(&root),
            (margin as i32, 5),
        )
        .map_err(|e| e.to_string())?;
        let (ox, oy) = (margin as i32, (title_h + margin) as i32);
        for y in 0..height {
            for x in 0..width {
                let col = match values[(y * width + x) as usize] {
                    Some(v) => false_colour(v / max),
                    None => [128, 128, 128],
                };
                let c = RGBColor(col[0], col[1], col[2]);
                for dy in 0..scale {
                    for dx in 0..scale {
                        root.draw_pixel(
                            (ox + (x * scale + dx) as i32, oy + (y * scale + dy) as i32),
                            &c,
                        )
                        .map_err(|e| e.to_string())?;
                    }
                }
            }
        }
        // Colour bar.
        let bx = ox + iw as i32 + 20;
        let bh = ih.max(200) as i32;
        for j in 0..bh {
            let t = 1.0 - j as f64 / (bh - 1).max(1) as f64;
            let col = false_colour(t);
            root.draw(&Rectangle::new(
                [(bx, oy + j), (bx + 20, oy + j + 1)],
                RGBColor(col[0], col[1], col[2]).filled(),
            ))
            .map_err(|e| e.to_string())?;
        }
        let style = ("sans-serif", 13).into_text_style(&root);
        for k in 0..=4 {
            let t = k as f64 / 4.0;
            let yy = oy + ((1.0 - t) * (bh - 1) as f64) as i32;
            root.draw_text(&format!("{:.3e}", t * max), &style, (bx + 26, yy - 6))
                .map_err(|e| e.to_string())?;
        }
        root.draw_text(label, &style, (bx - 10, oy + bh + 4))
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())
    };
    sss_util::write_atomic_with(
        path,
        |tmp| draw(tmp).map_err(draw_err),
        |e| draw_err(e.to_string()),
    )
}
