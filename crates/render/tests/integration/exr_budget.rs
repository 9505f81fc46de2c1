//! EXR sizes read from a file are checked against the memory budget before any pixel is read;
//! the layout `write_exr` writes (one part: `R,G,B` for the first layer, `name.R,name.G,name.B`
//! for the others) and the layouts `read_exr` reads (that one, and one part per layer).

use sss_bssrdf::Rgb;
use sss_render::image::{
    UNNAMED_LAYER, check_exr_budget, exr_bytes, read_exr, read_exr_attributes, read_exr_within,
    write_exr, write_exr_with,
};
use std::path::{Path, PathBuf};

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("sss-exr-budget-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// Rewrites the `dataWindow` attribute (OpenEXR file layout: name `dataWindow\0`, type
/// `box2i\0`, size 16 as i32 LE, then xMin, yMin, xMax, yMax as i32 LE) to 0..=max in x and y.
fn patch_data_window(bytes: &mut [u8], max: i32) {
    let key = b"dataWindow\0box2i\0";
    let at = bytes
        .windows(key.len())
        .position(|w| w == key)
        .expect("dataWindow attribute");
    let v = at + key.len() + 4;
    assert_eq!(&bytes[at + key.len()..v], &16i32.to_le_bytes());
    for (i, x) in [0i32, 0, max, max].iter().enumerate() {
        bytes[v + 4 * i..v + 4 * i + 4].copy_from_slice(&x.to_le_bytes());
    }
}

#[test]
fn header_estimate_matches_the_pixel_layout() {
    let dir = temp_dir("small");
    let path = dir.join("a.exr");
    let px = vec![[0.25f64, 0.5, 1.0]; 6 * 4];
    write_exr(&path, 6, 4, &[("beauty", &px), ("direct", &px)]).unwrap();
    // 2 layers × 24 pixels × (3 f32 channels = 12 bytes + one f64 RGB = 24 bytes).
    assert_eq!(exr_bytes(&path).unwrap(), 2 * 24 * (12 + 24));
    assert!(check_exr_budget(&[&path], 2 * 24 * 36).is_ok());
    let e = read_exr_within(&path, 2 * 24 * 36 - 1)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("1727 bytes") || e.contains("memory budget of 1727"),
        "{e}"
    );
    let (w, h, layers) = read_exr_within(&path, 1 << 20).unwrap();
    assert_eq!((w, h, layers.len()), (6, 4, 2));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_header_claiming_a_huge_data_window_is_refused_before_reading_pixels() {
    let dir = temp_dir("huge");
    let path = dir.join("huge.exr");
    let px = vec![[1.0f64; 3]; 4];
    write_exr(&path, 2, 2, &[("beauty", &px)]).unwrap();
    let mut bytes = std::fs::read(&path).unwrap();
    // 10⁹ × 10⁹ pixels (the format allows up to 2³⁰): 10¹⁸ × 36 bytes saturates the estimate.
    patch_data_window(&mut bytes, 999_999_999);
    std::fs::write(&path, &bytes).unwrap();
    assert_eq!(exr_bytes(&path).unwrap(), u64::MAX);
    let budget = 1u64 << 40;
    let e = read_exr_within(&path, budget).unwrap_err().to_string();
    assert!(e.contains("huge.exr"), "{e}");
    assert!(e.contains("1000000000x1000000000"), "{e}");
    assert!(
        e.contains(&format!("needs about {} bytes", u64::MAX)),
        "{e}"
    );
    assert!(e.contains(&format!("budget of {budget} bytes")), "{e}");
    // The default budget refuses it too.
    let e = read_exr(&path).unwrap_err().to_string();
    assert!(e.contains("memory budget"), "{e}");

    // A claim of 40000² pixels (1.6·10⁹ × 36 bytes ≈ 54 GiB) against a 1 GiB budget.
    patch_data_window(&mut bytes, 39_999);
    std::fs::write(&path, &bytes).unwrap();
    assert_eq!(exr_bytes(&path).unwrap(), 40_000u64 * 40_000 * 36);
    let e = read_exr_within(&path, 1 << 30).unwrap_err().to_string();
    assert!(
        e.contains("40000x40000") && e.contains("57600000000 bytes"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `n` pixels whose values differ per pixel, channel and `layer`, exactly representable in f32.
fn ramp(n: usize, layer: usize) -> Vec<Rgb> {
    (0..n)
        .map(|i| {
            let base = (100 * layer + i) as f64;
            [base + 0.25, base + 0.5, base + 0.75]
        })
        .collect()
}

#[test]
fn three_layers_round_trip_by_name_with_the_first_layer_first() {
    let dir = temp_dir("round-trip");
    let path = dir.join("three.exr");
    let (total, sub, err) = (ramp(12, 1), ramp(12, 2), ramp(12, 3));
    // Bad values are written as 0.
    let mut dirty = err.clone();
    dirty[5] = [f64::NAN, -1.0, f64::INFINITY];
    write_exr(
        &path,
        4,
        3,
        &[
            ("total", &total),
            ("subsurface", &sub),
            ("std_error", &dirty),
        ],
    )
    .unwrap();
    let (w, h, layers) = read_exr(&path).unwrap();
    assert_eq!((w, h), (4, 3));
    let names: Vec<&str> = layers.iter().map(|(n, _)| n.as_str()).collect();
    // The first layer is the plain R, G, B; the others follow in channel (alphabetical) order.
    assert_eq!(names, ["total", "std_error", "subsurface"]);
    let mut clean = err.clone();
    clean[5] = [0.0; 3];
    assert_eq!(layers[0].1, total);
    assert_eq!(layers[1].1, clean);
    assert_eq!(layers[2].1, sub);
    // The same image gives the same bytes.
    let again = dir.join("again.exr");
    write_exr(
        &again,
        4,
        3,
        &[
            ("total", &total),
            ("subsurface", &sub),
            ("std_error", &dirty),
        ],
    )
    .unwrap();
    assert_eq!(
        std::fs::read(&path).unwrap(),
        std::fs::read(&again).unwrap()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Header attributes round trip (sorted by name, UTF-8 kept); a file without
/// them has none; a bad or standard name is refused with nothing written.
#[test]
fn header_attributes_round_trip() {
    let dir = temp_dir("attributes");
    let path = dir.join("made.exr");
    let px = ramp(4, 0);
    let attrs = [
        ("sss/seed", "7".to_string()),
        ("sss/method", "pathtrace".to_string()),
        ("sss/scene", "scènes/π.toml".to_string()),
    ];
    write_exr_with(&path, 2, 2, &[("total", &px)], None, &attrs).unwrap();
    let got = read_exr_attributes(&path).unwrap();
    let want: Vec<(String, String)> = [
        ("sss/method", "pathtrace"),
        ("sss/scene", "scènes/π.toml"),
        ("sss/seed", "7"),
    ]
    .iter()
    .map(|(k, v)| (k.to_string(), v.to_string()))
    .collect();
    assert_eq!(got, want);
    assert_eq!(read_exr(&path).unwrap().2[0].1, px);
    let plain = dir.join("plain.exr");
    write_exr(&plain, 2, 2, &[("total", &px)]).unwrap();
    assert!(read_exr_attributes(&plain).unwrap().is_empty());
    for bad in [
        "",
        "compression",
        "has space",
        "a-name-of-more-than-31-characters",
    ] {
        let out = dir.join("bad.exr");
        let e = write_exr_with(
            &out,
            2,
            2,
            &[("total", &px)],
            None,
            &[(bad, "x".to_string())],
        )
        .unwrap_err();
        assert!(e.to_string().contains("bad.exr"), "{e}");
        assert!(!out.exists(), "{bad}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_written_file_is_one_part_with_layer_prefixed_channels() {
    let dir = temp_dir("one-part");
    let path = dir.join("one.exr");
    let px = ramp(6, 0);
    write_exr(
        &path,
        3,
        2,
        &[("total", &px), ("subsurface", &px), ("std_error", &px)],
    )
    .unwrap();
    let meta = exr::meta::MetaData::read_from_file(&path, false).unwrap();
    assert_eq!(meta.headers.len(), 1, "one part, not one per layer");
    let header = &meta.headers[0];
    let channels: Vec<String> = header
        .channels
        .list
        .iter()
        .map(|c| c.name.to_string())
        .collect();
    assert_eq!(
        channels,
        [
            "B",
            "G",
            "R",
            "std_error.B",
            "std_error.G",
            "std_error.R",
            "subsurface.B",
            "subsurface.G",
            "subsurface.R"
        ]
    );
    assert!(
        header
            .channels
            .list
            .iter()
            .all(|c| c.sample_type == exr::meta::attribute::SampleType::F32)
    );
    assert_eq!(
        header
            .own_attributes
            .layer_name
            .as_ref()
            .map(|n| n.to_string()),
        Some("total".to_string())
    );
    assert_eq!(
        (header.layer_size.0, header.layer_size.1),
        (3, 2),
        "image size"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn layer_names_that_cannot_round_trip_are_refused_and_nothing_is_written() {
    let dir = temp_dir("names");
    let path = dir.join("bad.exr");
    let px = ramp(4, 0);
    for (layers, why) in [
        (vec![("total", &px[..]), ("sub.surface", &px[..])], "'.'"),
        (vec![("to.tal", &px[..])], "'.'"),
        (vec![("total", &px[..]), ("", &px[..])], "empty"),
        (vec![("total", &px[..]), ("tötal", &px[..])], "ASCII"),
        (vec![("total", &px[..]), ("total", &px[..])], "twice"),
    ] {
        let e = write_exr(&path, 2, 2, &layers).unwrap_err();
        let msg = e.to_string();
        assert!(matches!(e, sss_render::Error::Input(_)), "{e:?}");
        assert!(msg.contains("bad.exr") && msg.contains(why), "{msg}");
        assert!(!path.exists(), "{layers:?} wrote a file");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// One part of a hand-built EXR: its name, if any, and its channels `(name, value)`.
type Part<'a> = (Option<&'a str>, &'a [(&'a str, f32)]);

/// Writes one part per `(part name, channels)`, each channel `(name, value)` of `w`x`h` f32
/// samples, as files of earlier versions and other tools are laid out.
fn write_parts(path: &Path, w: usize, h: usize, parts: &[Part]) {
    use exr::prelude::*;
    let layers: Vec<_> = parts
        .iter()
        .map(|(name, channels)| {
            let list = channels
                .iter()
                .map(|&(c, v)| AnyChannel::new(c, FlatSamples::F32(vec![v; w * h])))
                .collect();
            let attributes = match name {
                Some(n) => LayerAttributes::named(*n),
                None => LayerAttributes::default(),
            };
            Layer::new(
                Vec2(w, h),
                attributes,
                Encoding::UNCOMPRESSED,
                AnyChannels::sort(list),
            )
        })
        .collect();
    Image::from_layers(
        ImageAttributes::new(IntegerBounds::from_dimensions(Vec2(w, h))),
        layers,
    )
    .write()
    .to_file(path)
    .expect("write the test EXR");
}

#[test]
fn multi_part_files_of_earlier_versions_still_read_by_part_name() {
    let dir = temp_dir("multi-part");
    let path = dir.join("old.exr");
    write_parts(
        &path,
        3,
        2,
        &[
            (Some("total"), &[("R", 1.0), ("G", 2.0), ("B", 3.0)]),
            (Some("subsurface"), &[("R", 4.0), ("G", 5.0), ("B", 6.0)]),
            (
                Some("std_error"),
                &[("R", 7.0), ("G", 8.0), ("B", 9.0), ("A", 1.0)],
            ),
        ],
    );
    assert_eq!(
        exr::meta::MetaData::read_from_file(&path, false)
            .unwrap()
            .headers
            .len(),
        3
    );
    let (w, h, layers) = read_exr(&path).unwrap();
    assert_eq!((w, h), (3, 2));
    let names: Vec<&str> = layers.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, ["total", "subsurface", "std_error"]);
    for (k, (_, px)) in layers.iter().enumerate() {
        let v = 3.0 * k as f64;
        assert!(
            px.iter().all(|p| *p == [v + 1.0, v + 2.0, v + 3.0]),
            "{px:?}"
        );
    }
    // 3 parts × 6 px × (3 or 4 f32 channels + one f64 RGB copy).
    assert_eq!(exr_bytes(&path).unwrap(), 6 * (2 * (12 + 24) + (16 + 24)));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn plain_channels_of_an_unnamed_part_and_dotted_prefixes_read() {
    let dir = temp_dir("unnamed");
    let path = dir.join("blender.exr");
    // As Blender names its passes: view layer, pass, component; the last '.' splits.
    write_parts(
        &path,
        2,
        2,
        &[(
            None,
            &[
                ("R", 1.0),
                ("G", 2.0),
                ("B", 3.0),
                ("A", 1.0),
                ("ViewLayer.Combined.R", 4.0),
                ("ViewLayer.Combined.G", 5.0),
                ("ViewLayer.Combined.B", 6.0),
                ("ViewLayer.Combined.A", 1.0),
                ("ViewLayer.Depth.Z", 9.0),
                // Not a whole RGB layer: ignored.
                ("half.R", 9.0),
                ("half.G", 9.0),
            ],
        )],
    );
    let (w, h, layers) = read_exr(&path).unwrap();
    assert_eq!((w, h), (2, 2));
    let names: Vec<&str> = layers.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names, [UNNAMED_LAYER, "ViewLayer.Combined"]);
    assert_eq!(layers[0].1, vec![[1.0, 2.0, 3.0]; 4]);
    assert_eq!(layers[1].1, vec![[4.0, 5.0, 6.0]; 4]);
    let _ = std::fs::remove_dir_all(&dir);
}
