//! What the fuzz targets share: a per-process work directory for the files an input becomes.
//! Each target uses only part of it.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

/// This process's work directory for target `name`, created on first use: under
/// `$SSS_FUZZ_TMP` when set (`run.sh` points it at a folder it removes afterwards), else under
/// `/dev/shm` (memory, so writing an input costs no disk) or the system's temporary directory.
/// One per process, so parallel jobs (`-jobs=N`) do not overwrite each other's files.
pub fn work_dir(name: &str) -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let base = std::env::var_os("SSS_FUZZ_TMP")
            .map(PathBuf::from)
            .or_else(|| Some(PathBuf::from("/dev/shm")).filter(|p| p.is_dir()))
            .unwrap_or_else(std::env::temp_dir);
        let dir = base.join(format!("sss-fuzz-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir)
            .unwrap_or_else(|e| panic!("fuzz driver: cannot create {}: {e}", dir.display()));
        dir
    })
}

/// Writes `bytes` to `path`; a failure is the driver's, not the library's, so it panics with
/// a message that says so.
pub fn write(path: &Path, bytes: &[u8]) {
    std::fs::write(path, bytes)
        .unwrap_or_else(|e| panic!("fuzz driver: cannot write {}: {e}", path.display()));
}
