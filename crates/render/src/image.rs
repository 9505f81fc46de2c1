//! Image output: linear OpenEXR (one layer per quantity) and tone-mapped sRGB PNG (false-colour
//! error maps with a legend are drawn by `sss-plot`). Every file is written to a temporary name in the same directory
//! and renamed into place, so a crash never leaves a half-written image.

use crate::Error;
use sss_bssrdf::Rgb;
use std::path::Path;

fn io_err(path: &Path, what: &str, e: impl std::fmt::Display) -> Error {
    Error::Io {
        what: format!("{what} {}", path.display()),
        source: std::io::Error::other(e.to_string()),
    }
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
    let size = Vec2(w, h);
    let layers: Vec<_> = layers
        .iter()
        .map(|(name, data)| {
            let data: &[Rgb] = data;
            Layer::new(
                size,
                LayerAttributes::named(*name),
                // Blocks in increasing order: the parallel encoder otherwise writes them in the
                // order its threads finish, so the same image would give different files.
                Encoding {
                    line_order: LineOrder::Increasing,
                    ..Encoding::FAST_LOSSLESS
                },
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
    sss_util::write_atomic_with(
        path,
        |tmp| {
            image
                .write()
                .to_file(tmp)
                .map_err(|e| io_err(path, "writing", e))
        },
        |e| io_err(path, "writing", e),
    )
}

/// Named RGB layers of an image: (layer name, pixels).
pub type Layers = Vec<(String, Vec<Rgb>)>;

/// The estimated bytes of reading the OpenEXR file at `path` with [`read_exr`], from its
/// header alone (no pixel is read): per layer, width × height × (the bytes of one sample of
/// every channel, as the `exr` crate holds them: 2 for f16, 4 for f32 and u32, subsampled
/// channels counted at full size + 24 for the f64 RGB copy). Saturating, never overflowing.
pub fn exr_bytes(path: &Path) -> Result<u64, crate::Error> {
    let meta = exr::meta::MetaData::read_from_file(path, false)
        .map_err(|e| io_err(path, "reading the header of", e))?;
    Ok(meta_bytes(&meta))
}

fn meta_bytes(meta: &exr::meta::MetaData) -> u64 {
    let mut total = 0u64;
    for header in meta.headers.iter() {
        let pixels = (header.layer_size.0 as u64).saturating_mul(header.layer_size.1 as u64);
        let per_pixel = header
            .channels
            .list
            .iter()
            .map(|c| c.sample_type.bytes_per_sample() as u64)
            .sum::<u64>()
            + std::mem::size_of::<Rgb>() as u64;
        total = total.saturating_add(pixels.saturating_mul(per_pixel));
    }
    total
}

/// Fails, naming the file, its size and layers, the bytes needed and the budget, when reading
/// the EXR files `paths` together is estimated ([`exr_bytes`]) to need more than `budget`
/// bytes. Only the headers are read.
pub fn check_exr_budget(paths: &[&Path], budget: u64) -> Result<(), crate::Error> {
    let mut needed = 0u64;
    let mut what = Vec::new();
    for path in paths {
        let meta = exr::meta::MetaData::read_from_file(path, false)
            .map_err(|e| io_err(path, "reading the header of", e))?;
        let sizes: Vec<String> = meta
            .headers
            .iter()
            .map(|h| format!("{}x{}", h.layer_size.0, h.layer_size.1))
            .collect();
        what.push(format!(
            "{} ({} layer(s) of {})",
            path.display(),
            sizes.len(),
            sizes.join(", ")
        ));
        needed = needed.saturating_add(meta_bytes(&meta));
    }
    if needed > budget {
        return Err(crate::Error::Input(format!(
            "{} needs about {needed} bytes ({}) to read, over the memory budget of {budget} \
             bytes ({}); raise --max-memory if the file is genuine",
            what.join(" and "),
            crate::budget::human(needed),
            crate::budget::human(budget)
        )));
    }
    Ok(())
}

/// [`read_exr_within`] with the default budget ([`crate::budget::default_budget`]).
pub fn read_exr(path: &Path) -> Result<(u32, u32, Layers), crate::Error> {
    read_exr_within(path, crate::budget::default_budget())
}

/// Reads every RGB layer of an OpenEXR file, with the image size (width, height). The RGB
/// layers must all have that one size (an error names the file and the layers otherwise).
/// A file whose header says it needs more than `budget` bytes is refused before any pixel is
/// read ([`check_exr_budget`]).
pub fn read_exr_within(path: &Path, budget: u64) -> Result<(u32, u32, Layers), crate::Error> {
    use exr::prelude::*;
    check_exr_budget(&[path], budget)?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .map_err(|e| io_err(path, "reading", e))?;
    let mut out: self::Layers = Vec::new();
    let mut size = (0, 0);
    for layer in &image.layer_data {
        let (w, h) = (layer.size.0, layer.size.1);
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
            let this = (w as u32, h as u32);
            if let Some((first, _)) = out.first()
                && this != size
            {
                return Err(crate::Error::Input(format!(
                    "{}: layer `{name}` is {}x{} but layer `{first}` is {}x{}; every RGB layer \
                     must have the same size",
                    path.display(),
                    this.0,
                    this.1,
                    size.0,
                    size.1
                )));
            }
            size = this;
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
    let write = |tmp: &Path| {
        let file = std::fs::File::create(tmp).map_err(|e| io_err(path, "writing", e))?;
        let mut enc = png::Encoder::new(std::io::BufWriter::new(file), width, height);
        enc.set_color(png::ColorType::Rgb);
        enc.set_depth(png::BitDepth::Eight);
        let mut writer = enc.write_header().map_err(|e| io_err(path, "writing", e))?;
        writer
            .write_image_data(bytes)
            .map_err(|e| io_err(path, "writing", e))?;
        writer.finish().map_err(|e| io_err(path, "writing", e))
    };
    sss_util::write_atomic_with(path, write, |e| io_err(path, "writing", e))
}
