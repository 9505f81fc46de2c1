//! Value-level mutants of G-buffer EXRs: byte mutations of a compressed EXR mostly break its
//! chunks, so half of the `exr` target's inputs are instead valid EXR files written here
//! (with the `exr` crate directly, which, unlike `sss_render::image::write_exr`, keeps
//! negative and non-finite values) from mutated layers: extreme pixel values, layers of
//! different sizes, renamed, dropped or duplicated layers, either compression.

use super::corpus::gbuffer_layers;
use super::mutate::Rng;
use sss_bssrdf::Rgb;
use std::path::Path;

/// Extreme f32 pixel values.
const EXTREME_FLOATS: &[f32] = &[
    0.0,
    -0.0,
    -1.0,
    1.0,
    1e-30,
    1e30,
    f32::MAX,
    f32::MIN,
    f32::MIN_POSITIVE,
    1e-45,
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    16_777_217.0,
    4_294_967_296.0,
    0.5,
    1.5,
];

/// A named layer of `w`x`h` RGB pixels.
pub struct Layer {
    /// Its name.
    pub name: String,
    /// Width in pixels.
    pub w: usize,
    /// Height in pixels.
    pub h: usize,
    /// Row-major pixels.
    pub px: Vec<[f32; 3]>,
}

fn to_f32(px: &[Rgb]) -> Vec<[f32; 3]> {
    px.iter().map(|p| p.map(|v| v as f32)).collect()
}

/// Mutated G-buffer layers: sizes, names and values drawn from `rng`.
pub fn mutated_layers(rng: &mut Rng) -> Vec<Layer> {
    let sizes = [(8usize, 6usize), (1, 1), (3, 17), (16, 2)];
    let (w, h) = *rng.pick(&sizes);
    let (irr, surface) = gbuffer_layers(w, h);
    let mut layers = vec![
        Layer {
            name: "irradiance".into(),
            w,
            h,
            px: to_f32(&irr),
        },
        Layer {
            name: "surface".into(),
            w,
            h,
            px: to_f32(&surface),
        },
    ];
    for _ in 0..1 + rng.below(3) {
        let k = rng.below(layers.len());
        match rng.below(8) {
            0 => {
                // Another size for one layer.
                let (w2, h2) = *rng.pick(&sizes);
                let (a, b) = gbuffer_layers(w2, h2);
                let l = &mut layers[k];
                l.px = to_f32(if l.name == "surface" { &b } else { &a });
                (l.w, l.h) = (w2, h2);
            }
            1 => {
                layers[k].name = rng
                    .pick(&["", "total", "surface", "irradiance", "x"])
                    .to_string()
            }
            2 if layers.len() > 1 => {
                layers.remove(k);
            }
            3 if layers.len() < 4 => {
                let l = &layers[k];
                let copy = Layer {
                    name: l.name.clone(),
                    w: l.w,
                    h: l.h,
                    px: l.px.clone(),
                };
                layers.push(copy);
            }
            _ => {
                // Extreme values in a few pixels (all of them, sometimes).
                let l = &mut layers[k];
                let v = *rng.pick(EXTREME_FLOATS);
                let c = rng.below(3);
                if rng.one_in(4) {
                    l.px.iter_mut().for_each(|p| p[c] = v);
                } else {
                    for _ in 0..1 + rng.below(4) {
                        let i = rng.below(l.px.len());
                        l.px[i][c] = v;
                    }
                }
            }
        }
    }
    layers
}

/// Writes `layers` to `path` as one multi-layer EXR (each layer with its own size), raw or
/// run-length compressed.
pub fn write_layers(path: &Path, layers: &[Layer], compressed: bool) -> Result<(), String> {
    use exr::prelude::*;
    let (w, h) = layers
        .iter()
        .fold((1, 1), |(w, h), l| (w.max(l.w), h.max(l.h)));
    let encoding = if compressed {
        Encoding::FAST_LOSSLESS
    } else {
        Encoding::UNCOMPRESSED
    };
    let layers: Vec<_> = layers
        .iter()
        .map(|l| {
            let lw = l.w;
            let px = &l.px;
            exr::prelude::Layer::new(
                Vec2(l.w, l.h),
                LayerAttributes::named(l.name.as_str()),
                // Blocks in increasing order, so the same mutant gives the same bytes.
                Encoding {
                    line_order: LineOrder::Increasing,
                    ..encoding
                },
                SpecificChannels::rgb(move |Vec2(x, y): Vec2<usize>| {
                    let p = px[y * lw + x];
                    (p[0], p[1], p[2])
                }),
            )
        })
        .collect();
    let image = Image::from_layers(
        ImageAttributes::new(IntegerBounds::from_dimensions(Vec2(w, h))),
        layers,
    );
    image
        .write()
        .to_file(path)
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// A value-level mutant: mutated layers written to `path`, returned as bytes.
pub fn mutant(path: &Path, rng: &mut Rng) -> Result<Vec<u8>, String> {
    let layers = mutated_layers(rng);
    write_layers(path, &layers, rng.one_in(2))?;
    std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn value_mutants_are_deterministic_and_read_back() {
        let dir = std::env::temp_dir().join(format!("xtask-fuzz-exr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("m.exr");
        let mut read_ok = 0;
        for i in 0..40u64 {
            // Some mutants cannot be written (the writer refuses duplicate layer names; the
            // driver falls back to a byte mutant): the same ones in every run.
            let a = mutant(&path, &mut Rng::new(3, &[i]));
            let b = mutant(&path, &mut Rng::new(3, &[i]));
            assert_eq!(a, b, "mutant {i} differs between two runs");
            read_ok += (a.is_ok() && sss_render::image::read_exr(&path).is_ok()) as usize;
        }
        // Most mutants are valid EXR files (the point of value-level mutation).
        assert!(read_ok >= 20, "only {read_ok} of 40 mutants read back");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
