//! # sss-util: the few definitions every crate of the toolkit shares
//!
//! Use it when you need the toolkit's colour type, its seeding or its crash-safe file writes;
//! it has no dependencies, so depending on it costs nothing.
//!
//! - [`Rgb`], [`LUMINANCE`] and [`luminance`]: three linear colour channels and their Rec. 709
//!   luminance (ITU-R BT.709-6, Table 3 item 3.3), defined once for every crate.
//!
//! - [`splitmix64`] and [`splitmix64_mix`]: the SplitMix64 step and finaliser (Steele, Lea &
//!   Flood 2014, *Fast splittable pseudorandom number generators*, OOPSLA). Every random stream
//!   of the toolkit is seeded by hashing a user seed with a work-item index through them, never
//!   from a thread, so results are bit-identical for any thread count.
//! - `progress` (feature `progress`, which adds indicatif): progress bars on stderr with a time
//!   estimate that waits for evidence.
//! - [`human_bytes`]: a byte count as people read it (`1.5 GiB`), for memory-budget messages.
//! - [`write_atomic`] and [`write_atomic_with`]: write to a temporary file in the destination's
//!   directory, then rename it into place. A reader never sees a half-written file and a failed
//!   write leaves nothing behind.
//! - [`remove_temporaries`]: every temporary file of a write in flight is recorded in a
//!   process-wide registry ([`Temporary`]); a binary's Ctrl-C / SIGTERM handler calls this to
//!   delete them before it exits, so an interrupted run leaves no stray temporaries either.
//!   This crate installs no signal handler itself.
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

#![forbid(unsafe_code)]

#[cfg(feature = "progress")]
pub mod progress;

use std::io;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};

/// Three linear colour channels (red, green, blue).
pub type Rgb = [f64; 3];

/// Luminance weights of linear Rec. 709 RGB (ITU-R BT.709-6, Table 3 item 3.3): the scalar a
/// colour is sampled, clustered and error-controlled by.
pub const LUMINANCE: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// `LUMINANCE · c`, summed red, green, blue in that order.
#[inline]
pub fn luminance(c: Rgb) -> f64 {
    LUMINANCE[0] * c[0] + LUMINANCE[1] * c[1] + LUMINANCE[2] * c[2]
}

/// `n` bytes for a person, in powers of 1024 with one decimal: `512 B`, `1.5 KiB`, `3.0 GiB`.
pub fn human_bytes(n: u64) -> String {
    const UNITS: [&str; 5] = ["B", "KiB", "MiB", "GiB", "TiB"];
    let mut v = n as f64;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    if u == 0 {
        format!("{n} B")
    } else {
        format!("{v:.1} {}", UNITS[u])
    }
}

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

/// Temporary files of writes in flight, in registration order.
static LIVE: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

/// Makes every [`temp_path`] of this process distinct.
static COUNTER: AtomicU64 = AtomicU64::new(0);

fn live() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    // A panic while the lock was held cannot leave the list inconsistent (every operation is
    // a single push, remove or drain), so a poisoned lock is still usable.
    LIVE.lock().unwrap_or_else(|e| e.into_inner())
}

/// A temporary file path registered for [`remove_temporaries`] while this value lives.
/// Registering happens before the file is created and unregistering when the value is
/// dropped (after the rename, or after the failed write removed the file).
#[derive(Debug)]
pub struct Temporary {
    path: PathBuf,
}

impl Temporary {
    /// Registers `path` as a live temporary file (the file need not exist yet).
    pub fn register(path: PathBuf) -> Self {
        live().push(path.clone());
        Temporary { path }
    }

    /// The registered path.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Drop for Temporary {
    fn drop(&mut self) {
        let mut list = live();
        if let Some(i) = list.iter().rposition(|p| *p == self.path) {
            list.remove(i);
        }
    }
}

/// The temporary files registered right now (writes in flight), oldest first.
pub fn live_temporaries() -> Vec<PathBuf> {
    live().clone()
}

/// Deletes every registered temporary file and forgets them; returns how many files were
/// actually deleted (a registered path whose file was not created yet counts for nothing).
///
/// Meant for a Ctrl-C / SIGTERM handler that exits right after. A write in flight then finds
/// its temporary file gone and its rename fails, so no partial output is renamed into place;
/// the one remaining window is a writer that registered its path but creates the file between
/// this call and the process exit (microseconds).
pub fn remove_temporaries() -> usize {
    let paths: Vec<PathBuf> = live().drain(..).collect();
    paths
        .iter()
        .filter(|p| std::fs::remove_file(p).is_ok())
        .count()
}

/// The temporary path used for `path`: `.<name>.<pid>-<n>.tmp.<ext>` in the same directory
/// (so the rename is atomic) with the same extension (encoders that pick a format by
/// extension still work). `n` counts calls in this process, so two writes of one destination
/// at once (from two threads) never share a temporary file.
pub fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().into_owned())
        .unwrap_or_default();
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let tmp = format!(".{name}.{}-{n}.tmp.{ext}", std::process::id());
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.join(tmp),
        _ => PathBuf::from(tmp),
    }
}

/// Calls `write` with a temporary path next to `path`, then renames the temporary file onto
/// `path`. When `write` fails, or the rename does, the temporary file is removed and the error
/// returned; `path` is then untouched. `rename_err` turns the rename's I/O error into `E`.
/// The temporary path is registered (see [`Temporary`], [`remove_temporaries`]) from before
/// `write` is called until the rename or the clean-up is done.
pub fn write_atomic_with<E>(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
    rename_err: impl FnOnce(io::Error) -> E,
) -> Result<(), E> {
    let tmp = Temporary::register(temp_path(path));
    if let Err(e) = write(tmp.path()) {
        let _ = std::fs::remove_file(tmp.path());
        return Err(e);
    }
    std::fs::rename(tmp.path(), path).map_err(|e| {
        let _ = std::fs::remove_file(tmp.path());
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

    #[test]
    fn human_sizes() {
        assert_eq!(human_bytes(512), "512 B");
        assert_eq!(human_bytes(1023), "1023 B");
        assert_eq!(human_bytes(1536), "1.5 KiB");
        assert_eq!(human_bytes(3 << 30), "3.0 GiB");
        assert_eq!(human_bytes(u64::MAX), "16777216.0 TiB");
    }

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

    /// The registry is process-wide and `remove_temporaries` would delete another test's
    /// temporary in flight, so every test that writes files runs under this lock.
    static SERIAL: Mutex<()> = Mutex::new(());

    fn serial() -> std::sync::MutexGuard<'static, ()> {
        SERIAL.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("sss-util-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn atomic_write_replaces_and_leaves_no_temporary() {
        let _serial = serial();
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
        let _serial = serial();
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

    /// Tests share the process-wide registry; they look only at their own paths.
    fn registered(p: &Path) -> usize {
        live_temporaries().iter().filter(|q| *q == p).count()
    }

    #[test]
    fn temporary_is_registered_during_a_successful_write_and_forgotten_after() {
        let _serial = serial();
        let d = scratch("registry-ok");
        let p = d.join("c.txt");
        let mut seen = None;
        write_atomic_with(
            &p,
            |tmp| {
                seen = Some((tmp.to_path_buf(), registered(tmp)));
                std::fs::write(tmp, "x")
            },
            |e| e,
        )
        .unwrap();
        let (tmp, count) = seen.unwrap();
        assert_eq!(count, 1, "registered once while writing");
        assert_eq!(registered(&tmp), 0, "forgotten after the rename");
        assert!(!tmp.exists());
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "x");
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn temporary_is_forgotten_after_a_failed_write() {
        let _serial = serial();
        let d = scratch("registry-fail");
        let p = d.join("d.txt");
        let mut seen = None;
        let r: Result<(), String> = write_atomic_with(
            &p,
            |tmp| {
                std::fs::write(tmp, "partial").unwrap();
                seen = Some((tmp.to_path_buf(), registered(tmp)));
                Err("failed".into())
            },
            |e| e.to_string(),
        );
        assert!(r.is_err());
        let (tmp, count) = seen.unwrap();
        assert_eq!(count, 1);
        assert_eq!(registered(&tmp), 0);
        assert!(!tmp.exists() && !p.exists());
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn remove_temporaries_deletes_registered_files_only() {
        let _serial = serial();
        let d = scratch("registry-remove");
        let a = Temporary::register(d.join(".a.tmp"));
        let b = Temporary::register(d.join(".b.tmp"));
        let never_created = Temporary::register(d.join(".c.tmp"));
        std::fs::write(a.path(), "a").unwrap();
        std::fs::write(b.path(), "b").unwrap();
        let keep = d.join("keep.txt");
        std::fs::write(&keep, "k").unwrap();
        // Only this test touches the registry now (`serial`): exactly our two files.
        assert_eq!(remove_temporaries(), 2);
        assert!(!a.path().exists() && !b.path().exists());
        assert!(keep.exists(), "unregistered files stay");
        assert_eq!(registered(a.path()) + registered(never_created.path()), 0);
        // Dropping after the registry was emptied is harmless.
        drop((a, b, never_created));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn temp_paths_of_one_destination_are_distinct() {
        let _serial = serial();
        let p = Path::new("dir/same.exr");
        let names: std::collections::HashSet<PathBuf> = (0..100).map(|_| temp_path(p)).collect();
        assert_eq!(names.len(), 100);
        // Concurrent writes of one destination both succeed, and no temporary is left.
        let d = scratch("concurrent");
        let dest = d.join("same.txt");
        std::thread::scope(|s| {
            for k in 0..4 {
                let dest = &dest;
                s.spawn(move || {
                    write_atomic_with(
                        dest,
                        |tmp| {
                            std::fs::write(tmp, format!("{k}"))?;
                            std::thread::sleep(std::time::Duration::from_millis(20));
                            Ok(())
                        },
                        |e| e,
                    )
                    .unwrap()
                });
            }
        });
        let text = std::fs::read_to_string(&dest).unwrap();
        assert!(["0", "1", "2", "3"].contains(&text.as_str()), "{text}");
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 1);
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn unwritable_destination_is_an_error_not_a_panic() {
        let _serial = serial();
        let p = Path::new("/nonexistent-dir-sss-util/x.txt");
        assert!(write_atomic(p, b"x").is_err());
    }
}
