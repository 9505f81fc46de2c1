//! Inputs found by `cargo xtask fuzz` that once misbehaved, kept as regression tests.

use sss_render::image::{read_exr, write_exr};
use std::path::{Path, PathBuf};

/// A fresh, empty directory under the system temporary directory.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "sss-render-fuzz-regressions-{}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// Writes an EXR whose RGB layers have their own sizes: (name, width, height).
fn write_layers(path: &Path, layers: &[(&str, usize, usize)]) {
    use exr::prelude::*;
    let layers: Vec<_> = layers
        .iter()
        .map(|&(name, w, h)| {
            Layer::new(
                Vec2(w, h),
                LayerAttributes::named(name),
                Encoding::UNCOMPRESSED,
                SpecificChannels::rgb(move |Vec2(x, y): Vec2<usize>| {
                    ((x + w * y) as f32, 0.5f32, 1.0f32)
                }),
            )
        })
        .collect();
    Image::from_layers(
        ImageAttributes::new(IntegerBounds::from_dimensions(Vec2(8, 6))),
        layers,
    )
    .write()
    .to_file(path)
    .expect("write the test EXR");
}

/// Fuzzing (`cargo xtask fuzz --target exr`, seed 2) found G-buffers whose `irradiance` and
/// `surface` layers differ in size: `read_exr` returned the last layer's size with every
/// layer, and `sss filter` indexed the smaller layer out of bounds (a panic at
/// `crates/cli/src/commands/filter.rs:82`). Now `read_exr` refuses such a file with an error
/// naming the file and both layers, whichever layer is the smaller.
#[test]
fn layers_of_different_sizes_are_an_error_not_a_wrong_size() {
    let dir = temp_dir("sizes");
    for (i, layers) in [
        [("irradiance", 8, 6), ("surface", 4, 3)],
        [("irradiance", 1, 1), ("surface", 8, 6)],
        [("irradiance", 8, 6), ("surface", 6, 8)],
    ]
    .iter()
    .enumerate()
    {
        let path = dir.join(format!("mixed{i}.exr"));
        write_layers(&path, layers);
        let e = read_exr(&path).expect_err("layers of different sizes must be refused");
        let msg = e.to_string();
        assert!(msg.contains(&path.display().to_string()), "{msg}");
        assert!(
            msg.contains("`irradiance`") && msg.contains("`surface`"),
            "{msg}"
        );
        assert!(msg.contains("same size"), "{msg}");
        assert!(matches!(e, sss_render::Error::Input(_)), "{e:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Layers of one size still read, with that size; a non-RGB layer of another size neither
/// sets the size nor is refused.
#[test]
fn layers_of_one_size_still_read() {
    let dir = temp_dir("same");
    let path = dir.join("same.exr");
    write_layers(&path, &[("irradiance", 5, 3), ("surface", 5, 3)]);
    let (w, h, layers) = read_exr(&path).unwrap();
    assert_eq!((w, h), (5, 3));
    assert_eq!(layers.len(), 2);
    assert!(layers.iter().all(|(_, px)| px.len() == 15));

    let path = dir.join("written.exr");
    let px = vec![[1.0, 2.0, 3.0]; 6];
    write_exr(&path, 3, 2, &[("total", &px), ("subsurface", &px)]).unwrap();
    let (w, h, layers) = read_exr(&path).unwrap();
    assert_eq!((w, h, layers.len()), (3, 2, 2));
    let _ = std::fs::remove_dir_all(&dir);
}
