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

/// A diverging colour for t in [−1, 1]: blue (−1) through white (0) to red (+1), so that a
/// signed difference reads at a glance (too dark is blue, too bright red).
pub fn diverging_colour(t: f64) -> [u8; 3] {
    let t = if t.is_finite() {
        t.clamp(-1.0, 1.0)
    } else {
        0.0
    };
    // White to (59, 76, 192) below zero, white to (180, 4, 38) above (the end colours of
    // Moreland's cool-warm map).
    let (end, f) = if t < 0.0 {
        ([59.0, 76.0, 192.0], -t)
    } else {
        ([180.0, 4.0, 38.0], t)
    };
    [0, 1, 2].map(|k| (255.0 * (1.0 - f) + end[k] * f).round() as u8)
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
    let image = MapImage {
        path,
        width,
        height,
        values,
    };
    draw_scaled(&image, max, false, title, label)
}

/// Draws a map of signed per-pixel `values` (None: drawn grey) from −`max` (blue) through 0
/// (white) to +`max` (red) with a colour bar, as a PNG: where an image is darker or brighter
/// than its reference.
pub fn write_signed_map(
    path: &Path,
    width: u32,
    height: u32,
    values: &[Option<f64>],
    max: f64,
    title: &str,
    label: &str,
) -> Result<(), PlotError> {
    let image = MapImage {
        path,
        width,
        height,
        values,
    };
    draw_scaled(&image, max, true, title, label)
}

/// Where a map goes and what it shows.
struct MapImage<'a> {
    path: &'a Path,
    width: u32,
    height: u32,
    values: &'a [Option<f64>],
}

/// A map of `image`'s values over [0, max] in false colour, or over [−max, max] in the
/// diverging colours when `signed` (a non-positive or non-finite `max` counts as 1).
fn draw_scaled(
    image: &MapImage<'_>,
    max: f64,
    signed: bool,
    title: &str,
    label: &str,
) -> Result<(), PlotError> {
    let max = if max.is_finite() && max > 0.0 {
        max
    } else {
        1.0
    };
    let map = if signed {
        Map {
            colour: &|v| diverging_colour(v / max),
            bar: &|t| diverging_colour(2.0 * t - 1.0),
            tick: &|t| (2.0 * t - 1.0) * max,
        }
    } else {
        Map {
            colour: &|v| false_colour(v / max),
            bar: &|t| false_colour(t),
            tick: &|t| t * max,
        }
    };
    draw_map(image, &map, title, label)
}

/// How values become colours: a value's colour, the bar's colour at t ∈ [0, 1] (bottom to
/// top) and the value a bar position stands for.
struct Map<'a> {
    colour: &'a dyn Fn(f64) -> [u8; 3],
    bar: &'a dyn Fn(f64) -> [u8; 3],
    tick: &'a dyn Fn(f64) -> f64,
}

fn draw_map(
    image: &MapImage<'_>,
    map: &Map<'_>,
    title: &str,
    label: &str,
) -> Result<(), PlotError> {
    let MapImage {
        path,
        width,
        height,
        values,
    } = *image;
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
                    Some(v) => (map.colour)(v),
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
            let col = (map.bar)(t);
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
            root.draw_text(&format!("{:.3e}", (map.tick)(t)), &style, (bx + 26, yy - 6))
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_diverging_map_is_white_at_zero_and_darkens_towards_each_end() {
        assert_eq!(diverging_colour(0.0), [255, 255, 255]);
        assert_eq!(diverging_colour(-1.0), [59, 76, 192]);
        assert_eq!(diverging_colour(1.0), [180, 4, 38]);
        assert_eq!(diverging_colour(7.0), diverging_colour(1.0));
        assert_eq!(diverging_colour(f64::NAN), [255, 255, 255]);
        // Blue below zero, red above; farther from zero, farther from white.
        let sum = |c: [u8; 3]| c.iter().map(|&v| v as u32).sum::<u32>();
        let (a, b) = (diverging_colour(-0.3), diverging_colour(0.3));
        assert!(a[2] > a[0] && b[0] > b[2]);
        assert!(sum(diverging_colour(0.6)) < sum(b) && sum(diverging_colour(-0.6)) < sum(a));
    }

    #[test]
    fn a_signed_map_is_written_and_a_wrong_size_is_an_error() {
        let dir = std::env::temp_dir().join(format!("sss-plot-signed-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("d.png");
        let values: Vec<Option<f64>> = (0..12)
            .map(|i| (i != 5).then_some(i as f64 - 6.0))
            .collect();
        write_signed_map(&p, 4, 3, &values, 6.0, "signed", "Δ").unwrap();
        assert!(std::fs::metadata(&p).unwrap().len() > 100);
        let e = write_signed_map(&p, 5, 3, &values, 6.0, "signed", "Δ").unwrap_err();
        assert!(e.to_string().contains("12 values for a 5x3 image"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
