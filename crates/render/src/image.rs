//! Image output: linear OpenEXR (one layer per quantity), tone-mapped sRGB PNG, and false-colour
//! error maps with a legend. Every file is written to a temporary name in the same directory
//! and renamed into place, so a crash never leaves a half-written image.

use crate::Error;
use plotters::prelude::*;
use sss_bssrdf::Rgb;
use std::path::{Path, PathBuf};

fn io_err(path: &Path, what: &str, e: impl std::fmt::Display) -> Error {
    Error::Io {
        what: format!("{what} {}", path.display()),
        source: std::io::Error::other(e.to_string()),
    }
}

/// `dir/.name.<pid>.tmp.<ext>` next to `path`.
fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "image".into());
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = format!(".{name}.{}.tmp.{ext}", std::process::id());
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.join(tmp),
        _ => PathBuf::from(tmp),
    }
}

fn finish(tmp: &Path, path: &Path, result: Result<(), Error>) -> Result<(), Error> {
    if let Err(e) = result {
        let _ = std::fs::remove_file(tmp);
        return Err(e);
    }
    std::fs::rename(tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(tmp);
        io_err(path, "writing", e)
    })
}

/// Non-finite or negative values become 0 in every written image.
#[inline]
fn clean(v: f64) -> f32 {
    if v.is_finite() && v > 0.0 {
        v as f32
    } else {
        0.0
    }
}

/// Writes a linear OpenEXR file with one RGB f32 layer per `(name, pixels)` (row-major,
/// top-left first, `width·height` pixels each).
pub fn write_exr(
    path: &Path,
    width: u32,
    height: u32,
    layers: &[(&str, &[Rgb])],
) -> Result<(), crate::Error> {
    use exr::prelude::*;
    let (w, h) = (width as usize, height as usize);
    if layers.is_empty() || layers.iter().any(|(_, d)| d.len() != w * h) {
        return Err(crate::Error::Input(format!(
            "{}: image layers must hold {}x{} pixels",
            path.display(),
            width,
            height
        )));
    }
    let tmp = temp_path(path);
    let size = Vec2(w, h);
    let layers: Vec<_> = layers
        .iter()
        .map(|(name, data)| {
            let data: &[Rgb] = data;
            Layer::new(
                size,
                LayerAttributes::named(*name),
                Encoding::FAST_LOSSLESS,
                SpecificChannels::rgb(move |Vec2(x, y): Vec2<usize>| {
                    let p = data[y * w + x];
                    (clean(p[0]), clean(p[1]), clean(p[2]))
                }),
            )
        })
        .collect();
    let image = Image::from_layers(
        ImageAttributes::new(IntegerBounds::from_dimensions(size)),
        layers,
    );
    let result = image
        .write()
        .to_file(&tmp)
        .map_err(|e| io_err(path, "writing", e));
    finish(&tmp, path, result)
}

/// Named RGB layers of an image: (layer name, pixels).
pub type Layers = Vec<(String, Vec<Rgb>)>;

/// Reads every RGB layer of an OpenEXR file, with the image size (width, height).
pub fn read_exr(path: &Path) -> Result<(u32, u32, Layers), crate::Error> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .map_err(|e| io_err(path, "reading", e))?;
    let mut out = Vec::new();
    let mut size = (0, 0);
    for layer in &image.layer_data {
        let (w, h) = (layer.size.0, layer.size.1);
        size = (w as u32, h as u32);
        let mut px = vec![[0.0f64; 3]; w * h];
        let mut found = 0;
        for ch in &layer.channel_data.list {
            let c = match ch.name.to_string().as_str() {
                "R" => 0,
                "G" => 1,
                "B" => 2,
                _ => continue,
            };
            found += 1;
            for (i, v) in ch.sample_data.values_as_f32().enumerate().take(w * h) {
                px[i][c] = if v.is_finite() { v as f64 } else { 0.0 };
            }
        }
        if found == 3 {
            let name = layer
                .attributes
                .layer_name
                .as_ref()
                .map(|n| n.to_string())
                .unwrap_or_default();
            out.push((name, px));
        }
    }
    if out.is_empty() {
        return Err(crate::Error::Input(format!(
            "{}: no RGB layer",
            path.display()
        )));
    }
    Ok((size.0, size.1, out))
}

/// Linear → sRGB transfer (IEC 61966-2-1), for values in [0, 1].
fn srgb(v: f64) -> u8 {
    let v = if v.is_finite() {
        v.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5).floor().clamp(0.0, 255.0) as u8
}

/// A scale that maps the 99th percentile of the non-zero pixel luminances to 0.9 (1 if the
/// image is black).
pub fn auto_exposure(pixels: &[Rgb]) -> f64 {
    let mut lum: Vec<f64> = pixels
        .iter()
        .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
        .filter(|l| l.is_finite() && *l > 0.0)
        .collect();
    if lum.is_empty() {
        return 1.0;
    }
    lum.sort_by(f64::total_cmp);
    let p99 = lum[((lum.len() - 1) as f64 * 0.99) as usize];
    if p99 > 0.0 { 0.9 / p99 } else { 1.0 }
}

/// Writes `pixels` × `exposure` as an 8-bit sRGB PNG (values clipped to [0, 1]).
pub fn write_png(
    path: &Path,
    width: u32,
    height: u32,
    pixels: &[Rgb],
    exposure: f64,
) -> Result<(), Error> {
    let bytes: Vec<u8> = pixels
        .iter()
        .flat_map(|p| {
            [
                srgb(p[0] * exposure),
                srgb(p[1] * exposure),
                srgb(p[2] * exposure),
            ]
        })
        .collect();
    write_png_rgb8(path, width, height, &bytes)
}

/// Writes raw 8-bit RGB bytes as a PNG.
pub fn write_png_rgb8(path: &Path, width: u32, height: u32, bytes: &[u8]) -> Result<(), Error> {
    if bytes.len() != width as usize * height as usize * 3 {
        return Err(Error::Input(format!(
            "{}: wrong pixel count",
            path.display()
        )));
    }
    let tmp = temp_path(path);
    let result = (|| {
        let file = std::fs::File::create(&tmp).map_err(|e| io_err(path, "writing", e))?;
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(|e| io_err(path, "writing", e))?;
        writer
            .write_image_data(bytes)
            .map_err(|e| io_err(path, "writing", e))?;
        writer.finish().map_err(|e| io_err(path, "writing", e))
    })();
    finish(&tmp, path, result)
}

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
) -> Result<(), Error> {
    if values.len() != width as usize * height as usize {
        return Err(Error::Input(format!(
            "{}: wrong pixel count",
            path.display()
        )));
    }
    crate::plot::check_writable(path)?;
    let max = if max.is_finite() && max > 0.0 {
        max
    } else {
        1.0
    };
    let scale = (512 / width.max(height)).clamp(1, 8);
    let (iw, ih) = (width * scale, height * scale);
    let (bar_w, margin, title_h) = (150u32, 10u32, 30u32);
    let size = (iw + bar_w + 2 * margin, ih.max(200) + title_h + 2 * margin);
    let tmp = temp_path(path);
    let result = (|| -> Result<(), String> {
        crate::plot::ensure_font().map_err(|e| e.to_string())?;
        let root = BitMapBackend::new(&tmp, size).into_drawing_area();
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
    })();
    finish(&tmp, path, result.map_err(|m| io_err(path, "drawing", m)))
}
