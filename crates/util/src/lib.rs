//! # sss-util: the two utilities every crate of the toolkit shares
//!
//! Use it when you need the toolkit's seeding or its crash-safe file writes; it has no
//! dependencies, so depending on it costs nothing.
//!
//! - [`splitmix64`] and [`splitmix64_mix`]: the SplitMix64 step and finaliser (Steele, Lea &
//!   Flood 2014, *Fast splittable pseudorandom number generators*, OOPSLA). Every random stream
//!   of the toolkit is seeded by hashing a user seed with a work-item index through them, never
//!   from a thread, so results are bit-identical for any thread count.
//! - [`write_atomic`] and [`write_atomic_with`]: write to a temporary file in the destination's
//!   directory, then rename it into place. A reader never sees a half-written file and a failed
//!   write leaves nothing behind.
//!
//! ```
//! use sss_util::{splitmix64, write_atomic};
//!
//! // Independent seeds for work items 0 and 1 of a stream.
//! let (a, b) = (splitmix64(42 ^ 0), splitmix64(42 ^ 1));
//! assert_ne!(a, b);
//!
//! let dir = std::env::temp_dir().join(format!("sss-util-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir)?;
//! let path = dir.join("out.txt");
//! write_atomic(&path, b"hello")?;
//! assert_eq!(std::fs::read(&path)?, b"hello");
//! # std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), std::io::Error>(())
//! ```

use std::io;
use std::path::{Path, PathBuf};

/// The SplitMix64 golden-ratio increment, ⌊2⁶⁴/φ⌋ (odd).
pub const GOLDEN_GAMMA: u64 = 0x9e37_79b9_7f4a_7c15;

/// The SplitMix64 finaliser alone (the `mix64` variant 13 of Stafford, as used by SplitMix64):
/// a bijection of the 64-bit integers with full avalanche.
#[inline]
pub fn splitmix64_mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// One SplitMix64 output for state `z`: the finaliser of `z` + [`GOLDEN_GAMMA`] (Steele et al.
/// 2014). Bijective, so distinct inputs never collide.
#[inline]
pub fn splitmix64(z: u64) -> u64 {
    splitmix64_mix(z.wrapping_add(GOLDEN_GAMMA))
}

/// The temporary path used for `path`: `.<name>.<pid>.tmp.<ext>` in the same directory (so the
/// rename is atomic) with the same extension (encoders that pick a format by extension still
/// work).
pub fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
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

/// Calls `write` with a temporary path next to `path`, then renames the temporary file onto
/// `path`. When `write` fails, or the rename does, the temporary file is removed and the error
/// returned; `path` is then untouched. `rename_err` turns the rename's I/O error into `E`.
pub fn write_atomic_with<E>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
    rename_err: impl FnOnce(io::Error) -> E,
) -> Result<(), E> {
    let tmp = temp_path(path);
    if let Err(e) = write(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(e);
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        rename_err(e)
    })
}

/// Writes `bytes` to `path` through a temporary file and a rename (see [`write_atomic_with`]).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> io::Result<()> {
    write_atomic_with(path, |tmp| std::fs::write(tmp, bytes), |e| e)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Published SplitMix64 outputs: the reference C code (Vigna, splitmix64.c) seeded with 0
    /// yields these first three values; each call adds GOLDEN_GAMMA to the state.
    #[test]
    fn splitmix64_matches_the_reference_sequence() {
        let expected = [
            0xe220_a839_7b1d_cdaf_u64,
            0x6e78_9e6a_a1b9_65f4,
            0x06c4_5d18_8009_454f,
        ];
        let mut state = 0u64;
        for e in expected {
            assert_eq!(splitmix64(state), e);
            state = state.wrapping_add(GOLDEN_GAMMA);
        }
    }

    #[test]
    fn splitmix64_is_the_finaliser_of_the_incremented_state() {
        for z in [0u64, 1, 7, u64::MAX, 0x1234_5678_9abc_def0] {
            assert_eq!(splitmix64(z), splitmix64_mix(z.wrapping_add(GOLDEN_GAMMA)));
        }
        // The finaliser fixes 0 and nothing small.
        assert_eq!(splitmix64_mix(0), 0);
        assert_ne!(splitmix64_mix(1), 1);
    }

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("sss-util-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn atomic_write_replaces_and_leaves_no_temporary() {
        let d = scratch("replace");
        let p = d.join("a.csv");
        std::fs::write(&p, "old").unwrap();
        write_atomic(&p, b"new").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "new");
        let names: Vec<_> = std::fs::read_dir(&d).unwrap().collect();
        assert_eq!(names.len(), 1, "only the destination remains");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn failed_write_keeps_the_old_file_and_removes_the_temporary() {
        let d = scratch("fail");
        let p = d.join("b.exr");
        std::fs::write(&p, "old").unwrap();
        let r: Result<(), String> = write_atomic_with(
            &p,
            |tmp| {
                std::fs::write(tmp, "partial").unwrap();
                Err("encoder failed".into())
            },
            |e| e.to_string(),
        );
        assert_eq!(r.unwrap_err(), "encoder failed");
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "old");
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn temp_path_keeps_directory_and_extension() {
        let t = temp_path(Path::new("out/dir/img.png"));
        assert_eq!(t.parent(), Some(Path::new("out/dir")));
        assert_eq!(t.extension().and_then(|e| e.to_str()), Some("png"));
        assert!(
            t.file_name()
                .unwrap()
                .to_string_lossy()
                .starts_with(".img.png.")
        );
        let bare = temp_path(Path::new("x.csv"));
        assert!(bare.parent().is_none_or(|p| p.as_os_str().is_empty()));
    }

    #[test]
    fn unwritable_destination_is_an_error_not_a_panic() {
        let p = Path::new("/nonexistent-dir-sss-util/x.txt");
        assert!(write_atomic(p, b"x").is_err());
    }
}
