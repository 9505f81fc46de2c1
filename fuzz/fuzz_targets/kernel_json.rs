//! `sss_separable::kernel_json::KernelFile::from_json` on the input as UTF-8 text. A file that
//! reads must write back to text that reads to the same file, and its kernel, when it builds,
//! must be finite.
#![no_main]

use libfuzzer_sys::fuzz_target;
use sss_separable::kernel_json::KernelFile;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(file) = KernelFile::from_json(text) else {
        return;
    };
    let written = file
        .to_json()
        .expect("a file that reads has only finite numbers");
    let back = KernelFile::from_json(&written).expect("the written text reads back");
    assert_eq!(back, file, "write then read changed the file");
    if let Ok(kernel) = file.kernel() {
        assert!(
            kernel.is_finite(),
            "the kernel of a file that reads is finite"
        );
        assert!(
            kernel.total_weight().iter().all(|e| e.is_finite()),
            "the kernel's energy is finite"
        );
    }
});
