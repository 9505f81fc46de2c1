//! `sss_render::image::read_exr_within` on the input as an OpenEXR file, with a memory budget
//! of 64 MiB (a header announcing a huge image is refused before any pixel is read), and
//! `read_exr_attributes` (the header's text attributes). A file that reads must give layers
//! of width × height finite pixels.
#![no_main]

mod common;

use libfuzzer_sys::fuzz_target;
use sss_render::image::{read_exr_attributes, read_exr_within};

/// The memory budget of a read: far above the seeds' few KB, far below the fuzzer's 2 GB
/// RSS limit.
const BUDGET: u64 = 64 << 20;

fuzz_target!(|data: &[u8]| {
    let path = common::work_dir("exr").join("in.exr");
    common::write(&path, data);
    let _ = read_exr_attributes(&path);
    if let Ok((w, h, layers)) = read_exr_within(&path, BUDGET) {
        assert!(!layers.is_empty(), "a read image has at least one layer");
        for (name, px) in &layers {
            assert_eq!(px.len(), w as usize * h as usize, "layer `{name}`");
            assert!(
                px.iter().flatten().all(|v| v.is_finite()),
                "layer `{name}` has a non-finite value"
            );
        }
    }
});
