//! Image output: linear OpenEXR (one part, one RGB layer per quantity: `R,G,B` for the first,
//! `name.R,name.G,name.B` for the others) and tone-mapped sRGB PNG (false-colour
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

/// The layer name given to plain `R`, `G`, `B` channels of a part that has no `name`
/// attribute (or an empty one), when reading ([`read_exr_within`]).
pub const UNNAMED_LAYER: &str = "beauty";

/// Why `name` cannot be a layer name of [`write_exr`], if it cannot: it must be non-empty
/// printable ASCII without a '.' (the '.' separates layer and channel in `layer.R`, and
/// readers split channel names at the last '.').
fn bad_layer_name(name: &str) -> Option<&'static str> {
    if name.is_empty() {
        Some("is empty")
    } else if name.contains('.') {
        Some("contains a '.' (it separates layer and channel in `layer.R`)")
    } else if !name.bytes().all(|b| b.is_ascii_graphic() || b == b' ') {
        Some("is not printable ASCII")
    } else {
        None
    }
}

/// Writes a linear OpenEXR file of f32 RGB layers, one `(name, pixels)` each (row-major,
/// top-left first, `width·height` pixels each), as ONE part (one header), as Blender's
/// multilayer EXR, Nuke and Mitsuba's AOVs do, so that readers which see only the first part
/// (the classic `OpenEXR.InputFile`, pyexr) see every layer: the first layer (the "beauty")
/// is the plain channels `R`, `G`, `B` and its name is the part's `name` attribute; every
/// other layer is the channels `name.R`, `name.G`, `name.B`. [`read_exr_within`] gives the
/// layers back by name, the beauty first.
///
/// Layer names must be distinct, non-empty printable ASCII without a '.': anything else is an
/// error naming the file and the layer, and nothing is written. So is an empty `layers` or a
/// layer not of `width·height` pixels. Non-finite and negative values are written as 0. The
/// blocks are written in increasing order, so the same image always gives the same bytes. The
/// file is written under a temporary name and renamed into place.
///
/// Versions before this layout wrote one part per layer; those files still read
/// ([`read_exr_within`]).
pub fn write_exr(
    path: &Path,
    width: u32,
    height: u32,
    layers: &[(&str, &[Rgb])],
) -> Result<(), crate::Error> {
    write_exr_with(path, width, height, layers, None, &[])
}

/// [`write_exr`] with text attributes in the header, `(name, value)` each: how the image was
/// made, say (`sss render` writes `sss/method`, `sss/seed`, ...; [`read_exr_attributes`]
/// gives them back). Values are written as UTF-8 bytes (OpenEXR's own library reads a text
/// attribute as a `std::string` of bytes). A name must be 1 to 31 printable ASCII characters,
/// not one of the standard attributes'; otherwise an error, nothing written.
///
/// `alpha`, when given (`width·height` values, clamped to [0, 1]), is the channel `A` beside
/// the beauty's `R`, `G`, `B`: for `sss render`, the fraction of each pixel's camera samples
/// that hit an object (the silhouette, as other renderers' film alpha). The colour layers are
/// not premultiplied by it: the beauty holds the environment where rays missed.
pub fn write_exr_with(
    path: &Path,
    width: u32,
    height: u32,
    layers: &[(&str, &[Rgb])],
    alpha: Option<&[f32]>,
    attributes: &[(&str, String)],
) -> Result<(), crate::Error> {
    use exr::prelude::*;
    const STANDARD: [&str; 12] = [
        "channels",
        "compression",
        "dataWindow",
        "displayWindow",
        "lineOrder",
        "pixelAspectRatio",
        "screenWindowCenter",
        "screenWindowWidth",
        "name",
        "type",
        "chunkCount",
        "tiles",
    ];
    let utf8 = |t: &str| -> Text { Text::from_slice_unchecked(t.as_bytes()) };
    for (i, (name, _)) in attributes.iter().enumerate() {
        let bad = name.is_empty()
            || name.len() > 31
            || !name.bytes().all(|b| b.is_ascii_graphic())
            || STANDARD.contains(name)
            || attributes[..i].iter().any(|(n, _)| n == name);
        if bad {
            return Err(crate::Error::Input(format!(
                "{}: cannot write header attribute `{name}`: names must be distinct, 1 to 31 \
                 printable ASCII characters and not a standard attribute's",
                path.display()
            )));
        }
    }
    let (w, h) = (width as usize, height as usize);
    if layers.is_empty()
        || layers.iter().any(|(_, d)| d.len() != w * h)
        || alpha.is_some_and(|a| a.len() != w * h)
    {
        return Err(crate::Error::Input(format!(
            "{}: image layers must hold {}x{} pixels",
            path.display(),
            width,
            height
        )));
    }
    for (i, (name, _)) in layers.iter().enumerate() {
        if let Some(why) = bad_layer_name(name) {
            return Err(crate::Error::Input(format!(
                "{}: cannot write layer `{name}`: its name {why}; layer names must be \
                 non-empty printable ASCII without '.'",
                path.display()
            )));
        }
        if layers[..i].iter().any(|(n, _)| n == name) {
            return Err(crate::Error::Input(format!(
                "{}: cannot write layer `{name}` twice; layer names must be distinct",
                path.display()
            )));
        }
    }
    let size = Vec2(w, h);
    let mut channels = SmallVec::<[AnyChannel<FlatSamples>; 4]>::new();
    for (k, (name, data)) in layers.iter().enumerate() {
        for (c, suffix) in ["R", "G", "B"].iter().enumerate() {
            let samples: Vec<f32> = data.iter().map(|p| clean(p[c])).collect();
            let channel = if k == 0 {
                (*suffix).to_string()
            } else {
                format!("{name}.{suffix}")
            };
            channels.push(AnyChannel::new(
                Text::new_or_panic(channel),
                FlatSamples::F32(samples),
            ));
        }
    }
    if let Some(a) = alpha {
        let samples: Vec<f32> = a
            .iter()
            .map(|&v| {
                if v.is_finite() {
                    v.clamp(0.0, 1.0)
                } else {
                    0.0
                }
            })
            .collect();
        channels.push(AnyChannel::new(
            Text::new_or_panic("A"),
            FlatSamples::F32(samples),
        ));
    }
    let mut header = LayerAttributes::named(Text::new_or_panic(layers[0].0));
    for (name, value) in attributes {
        header
            .other
            .insert(utf8(name), AttributeValue::Text(utf8(value)));
    }
    let layer = Layer::new(
        size,
        header,
        // Blocks in increasing order: the parallel encoder otherwise writes them in the order
        // its threads finish, so the same image would give different files.
        Encoding {
            line_order: LineOrder::Increasing,
            ..Encoding::FAST_LOSSLESS
        },
        AnyChannels::sort(channels),
    );
    let image = Image::from_layer(layer);
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

/// The text attributes of an OpenEXR file's first header that are not standard ones, `(name,
/// value)` sorted by name, the values read as UTF-8 (invalid bytes as U+FFFD): what
/// [`write_exr_with`] wrote, or another renderer's.
pub fn read_exr_attributes(path: &Path) -> Result<Vec<(String, String)>, crate::Error> {
    use exr::meta::attribute::AttributeValue;
    let meta =
        exr::meta::MetaData::read_from_file(path, false).map_err(|e| io_err(path, "reading", e))?;
    let Some(header) = meta.headers.first() else {
        return Ok(Vec::new());
    };
    let mut out: Vec<(String, String)> = header
        .own_attributes
        .other
        .iter()
        .chain(header.shared_attributes.other.iter())
        .filter_map(|(k, v)| match v {
            AttributeValue::Text(t) => Some((
                k.to_string(),
                String::from_utf8_lossy(t.as_slice()).into_owned(),
            )),
            _ => None,
        })
        .collect();
    out.sort();
    Ok(out)
}

/// Named RGB layers of an image: (layer name, pixels).
pub type Layers = Vec<(String, Vec<Rgb>)>;

/// Splits a channel name into (layer, component) at its last '.': `subsurface.R` is layer
/// `subsurface`, component `R`; a name without '.' (`R`) has no layer. Only the components
/// `R`, `G` and `B` are RGB channels (index 0, 1, 2); anything else is `None`.
fn rgb_channel(name: &str) -> Option<(Option<&str>, usize)> {
    let (layer, component) = match name.rfind('.') {
        Some(at) => (Some(&name[..at]), &name[at + 1..]),
        None => (None, name),
    };
    let c = match component {
        "R" => 0,
        "G" => 1,
        "B" => 2,
        _ => return None,
    };
    Some((layer, c))
}

/// How many RGB layers a part holds, as [`read_exr_within`] counts them (an upper bound):
/// its channels named `R` or `*.R`.
fn rgb_layer_count(header: &exr::meta::header::Header) -> u64 {
    header
        .channels
        .list
        .iter()
        .filter(|c| matches!(rgb_channel(&c.name.to_string()), Some((_, 0))))
        .count() as u64
}

/// The estimated bytes of reading the OpenEXR file at `path` with [`read_exr`], from its
/// header alone (no pixel is read): per part, width × height × (the bytes of one sample of
/// every channel, as the `exr` crate holds them: 2 for f16, 4 for f32 and u32, subsampled
/// channels counted at full size + 24 for the f64 RGB copy of each RGB layer, counted as the
/// channels named `R` or `*.R`). Saturating, never overflowing.
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
            .saturating_add(
                rgb_layer_count(header).saturating_mul(std::mem::size_of::<Rgb>() as u64),
            );
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
        let layers: u64 = meta.headers.iter().map(rgb_layer_count).sum();
        what.push(format!(
            "{} ({layers} layer(s) in {} part(s) of {})",
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

/// The alpha channel of an OpenEXR file: the plain channel `A` of its first part (as
/// [`write_exr_with`] writes beside the beauty, and other renderers' RGBA films), row-major
/// from the top-left, non-finite values read as 0; `None` when the file has none. Refused
/// before any pixel is read when its header needs more than the default memory budget.
pub fn read_exr_alpha(path: &Path) -> Result<Option<Vec<f32>>, crate::Error> {
    use exr::prelude::*;
    check_exr_budget(&[path], crate::budget::default_budget())?;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| io_err(path, "reading", e))?;
    let part = &image.layer_data;
    Ok(part
        .channel_data
        .list
        .iter()
        .find(|ch| ch.name.to_string() == "A")
        .map(|ch| {
            ch.sample_data
                .values_as_f32()
                .map(|v| if v.is_finite() { v } else { 0.0 })
                .collect()
        }))
}

/// Reads every RGB layer of an OpenEXR file, with the image size (width, height).
///
/// Both layouts read: one part holding every layer (as [`write_exr`] writes, and Blender,
/// Nuke and Mitsuba), and one part per layer (as versions before it wrote). In every part,
/// each channel name is split at its last '.': the prefix is the layer name and the suffix
/// must be `R`, `G` or `B` (other channels, such as `A` or `Z`, are ignored); plain `R`, `G`,
/// `B` belong to the layer named by the part's `name` attribute, or [`UNNAMED_LAYER`]
/// (`beauty`) when the part has no name (or an empty one). A layer is read when it has all
/// three of `R`, `G` and `B`. The layers come in file order, part by part, each part's plain
/// layer first, then its prefixed layers in channel order (alphabetical, as EXR stores
/// channels). A name found twice gives two layers; callers that look layers up by name take
/// the first.
///
/// The RGB layers must all have one size (an error names the file and the layers otherwise).
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
    for part in &image.layer_data {
        let (w, h) = (part.size.0, part.size.1);
        let plain = part
            .attributes
            .layer_name
            .as_ref()
            .map(|n| n.to_string())
            .filter(|n| !n.is_empty())
            .unwrap_or_else(|| UNNAMED_LAYER.to_string());
        // (layer name, channel index of R, G, B in this part), the plain layer first.
        let mut found: Vec<(String, [Option<usize>; 3])> = vec![(plain, [None; 3])];
        for (k, ch) in part.channel_data.list.iter().enumerate() {
            let name = ch.name.to_string();
            let Some((layer, c)) = rgb_channel(&name) else {
                continue;
            };
            let slot = match layer {
                None => 0,
                Some(layer) => match found.iter().skip(1).position(|(n, _)| n == layer) {
                    Some(i) => i + 1,
                    None => {
                        found.push((layer.to_string(), [None; 3]));
                        found.len() - 1
                    }
                },
            };
            found[slot].1[c] = Some(k);
        }
        for (name, rgb) in found {
            let [Some(r), Some(g), Some(b)] = rgb else {
                continue;
            };
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
            let mut px = vec![[0.0f64; 3]; w * h];
            for (c, k) in [r, g, b].into_iter().enumerate() {
                let samples = part.channel_data.list[k].sample_data.values_as_f32();
                for (i, v) in samples.enumerate().take(w * h) {
                    px[i][c] = if v.is_finite() { v as f64 } else { 0.0 };
                }
            }
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

/// Parses an exposure (the `--exposure` of every command that writes PNGs): the scale each
/// linear pixel value is multiplied by before the sRGB curve, a finite number > 0.
pub fn parse_exposure(text: &str) -> Result<f64, String> {
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!(
            "`{text}` is not an exposure: a finite scale > 0 (pixel values are multiplied by it)"
        )),
    }
}

/// `exposure`, or where it is `None` the automatic one of `pixels` ([`auto_exposure`]).
pub fn exposure_or_auto(exposure: Option<f64>, pixels: &[Rgb]) -> f64 {
    exposure.unwrap_or_else(|| auto_exposure(pixels))
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
