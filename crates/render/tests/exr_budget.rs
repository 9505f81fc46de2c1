//! EXR sizes read from a file are checked against the memory budget before any pixel is read.

use sss_render::image::{check_exr_budget, exr_bytes, read_exr, read_exr_within, write_exr};
use std::path::PathBuf;

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
