//! Checked cache entries: every file `compare` caches under `<out>/cache/` has a sidecar
//! `<file>.sum` holding its length and FNV-1a 64 checksum, written (atomically) after the
//! entry itself. A reader trusts an entry only when the sidecar exists and both figures match
//! the bytes on disk; a truncated, altered or unsealed entry (one whose writer was interrupted
//! between the entry and its sidecar) is reported as corrupt and recomputed.
//!
//! FNV-1a is the Fowler–Noll–Vo hash, variant 1a, 64 bits (offset basis 0xcbf29ce484222325,
//! prime 2⁴⁰ + 2⁸ + 0xb3; Fowler, Noll & Vo, IETF draft-eastlake-fnv). It is not
//! cryptographic: it detects accidental damage, which is all a local cache needs.

use super::Error;
use super::output::write_atomic;
use std::path::{Path, PathBuf};

/// First word of a sidecar; bump the version when its layout changes.
const SUM_HEADER: &str = "sss-cache-sum v1";

/// FNV-1a 64 of `bytes` (see the module documentation).
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= *b as u64;
        h = h.wrapping_mul(0x100_0000_01b3);
    }
    h
}

/// The sidecar of `entry`: its path with `.sum` appended.
pub fn sum_path(entry: &Path) -> PathBuf {
    let mut s = entry.as_os_str().to_owned();
    s.push(".sum");
    PathBuf::from(s)
}

fn sum_text(bytes: &[u8]) -> String {
    format!(
        "{SUM_HEADER} len={} fnv1a64={:016x}\n",
        bytes.len(),
        fnv1a64(bytes)
    )
}

/// Writes the sidecar of `entry`, which must be complete on disk (written atomically).
pub fn seal(entry: &Path) -> Result<(), Error> {
    let bytes = std::fs::read(entry)
        .map_err(|e| Error(format!("cannot read back '{}': {e}", entry.display())))?;
    write_atomic(&sum_path(entry), sum_text(&bytes).as_bytes())
}

/// Writes `bytes` to `entry` atomically, then its sidecar.
pub fn write_entry(entry: &Path, bytes: &[u8]) -> Result<(), Error> {
    write_atomic(entry, bytes)?;
    write_atomic(&sum_path(entry), sum_text(bytes).as_bytes())
}

/// What a cache reader returned (`Ok(None)`: no entry) as the entry to use: a corrupt entry
/// is reported through `log` as `{subject}: cached {what} is corrupt (…), recomputing` and
/// treated as absent, so every cache says the same thing when it recomputes.
pub fn usable<T>(
    read: Result<Option<T>, String>,
    subject: &str,
    what: &str,
    log: &dyn Fn(&str),
) -> Option<T> {
    read.unwrap_or_else(|reason| {
        log(&format!(
            "{subject}: cached {what} is corrupt ({reason}), recomputing"
        ));
        None
    })
}

/// What a cache look-up found.
#[derive(Debug, PartialEq)]
pub enum Entry {
    /// No entry: compute it (nothing to report).
    Missing,
    /// An entry that must not be trusted, and why.
    Corrupt(String),
    /// The entry's bytes, matching its sidecar.
    Good(Vec<u8>),
}

/// Reads `entry` and checks it against its sidecar.
pub fn check(entry: &Path) -> Entry {
    let bytes = match std::fs::read(entry) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Entry::Missing,
        Err(e) => return Entry::Corrupt(format!("unreadable: {e}")),
    };
    let sum = match std::fs::read_to_string(sum_path(entry)) {
        Ok(s) => s,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Entry::Corrupt("no checksum file".into());
        }
        Err(e) => return Entry::Corrupt(format!("unreadable checksum file: {e}")),
    };
    let mut words = sum.split_whitespace();
    let header = [words.next(), words.next()];
    let len = words
        .next()
        .and_then(|w| w.strip_prefix("len="))
        .and_then(|v| v.parse::<u64>().ok());
    let hash = words
        .next()
        .and_then(|w| w.strip_prefix("fnv1a64="))
        .and_then(|v| u64::from_str_radix(v, 16).ok());
    let (Some(len), Some(hash)) = (len, hash) else {
        return Entry::Corrupt("malformed checksum file".into());
    };
    if header.map(Option::unwrap_or_default).join(" ") != SUM_HEADER || words.next().is_some() {
        return Entry::Corrupt("malformed checksum file".into());
    }
    if bytes.len() as u64 != len {
        return Entry::Corrupt(format!("{} bytes, {len} expected", bytes.len()));
    }
    if fnv1a64(&bytes) != hash {
        return Entry::Corrupt("checksum mismatch".into());
    }
    Entry::Good(bytes)
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    #[test]
    fn a_corrupt_entry_is_reported_and_recomputed() {
        let lines = std::cell::RefCell::new(Vec::new());
        let log = |l: &str| lines.borrow_mut().push(l.to_string());
        assert_eq!(usable(Ok(Some(7)), "scene s", "reference", &log), Some(7));
        assert_eq!(usable::<i32>(Ok(None), "scene s", "reference", &log), None);
        assert!(
            lines.borrow().is_empty(),
            "a usable or absent entry logs nothing"
        );
        let bad = Err("length 3, sum says 4".to_string());
        assert_eq!(usable::<i32>(bad, "scene s", "reference", &log), None);
        assert_eq!(
            *lines.borrow(),
            ["scene s: cached reference is corrupt (length 3, sum says 4), recomputing"]
        );
    }

    /// A fresh scratch directory for a test.
    pub(in super::super) fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("xtask-cache-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// Flips the lowest bit of byte `at` of `path`.
    pub(in super::super) fn flip_byte(path: &Path, at: usize) {
        let mut b = std::fs::read(path).unwrap();
        b[at] ^= 1;
        std::fs::write(path, b).unwrap();
    }

    /// Cuts `path` to its first `len` bytes.
    pub(in super::super) fn truncate(path: &Path, len: u64) {
        std::fs::OpenOptions::new()
            .write(true)
            .open(path)
            .unwrap()
            .set_len(len)
            .unwrap();
    }

    /// The published FNV-1a 64 test vectors (Fowler–Noll–Vo reference test suite).
    #[test]
    fn fnv1a64_matches_published_vectors() {
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a64(b"foobar"), 0x8594_4171_f739_67e8);
    }

    #[test]
    fn good_entry_round_trips() {
        let d = scratch("good");
        let p = d.join("e.csv");
        assert_eq!(check(&p), Entry::Missing);
        write_entry(&p, b"1,2,3\n").unwrap();
        assert_eq!(check(&p), Entry::Good(b"1,2,3\n".to_vec()));
        // Sealing a file written some other way works the same.
        let q = d.join("f.bin");
        std::fs::write(&q, [0u8, 255, 7]).unwrap();
        seal(&q).unwrap();
        assert_eq!(check(&q), Entry::Good(vec![0, 255, 7]));
        std::fs::remove_dir_all(&d).unwrap();
    }

    fn corrupt_reason(e: Entry) -> String {
        match e {
            Entry::Corrupt(r) => r,
            other => panic!("expected a corrupt entry, got {other:?}"),
        }
    }

    #[test]
    fn damaged_entries_are_rejected_with_a_reason() {
        let d = scratch("damaged");
        let p = d.join("e.txt");
        let body = b"0.5 1234\n";

        write_entry(&p, body).unwrap();
        truncate(&p, 4);
        assert_eq!(corrupt_reason(check(&p)), "4 bytes, 9 expected");

        write_entry(&p, body).unwrap();
        flip_byte(&p, 2); // '5' -> '4': same length, different value
        assert_eq!(corrupt_reason(check(&p)), "checksum mismatch");

        write_entry(&p, body).unwrap();
        std::fs::remove_file(sum_path(&p)).unwrap();
        assert_eq!(corrupt_reason(check(&p)), "no checksum file");

        // An entry rewritten without its sidecar (interrupted between the two writes) no
        // longer matches the old sidecar.
        write_entry(&p, body).unwrap();
        std::fs::write(&p, b"0.5 1235\n").unwrap();
        assert_eq!(corrupt_reason(check(&p)), "checksum mismatch");

        for bad in [
            "",
            "sss-cache-sum v1 len=9\n",
            "sss-cache-sum v2 len=9 fnv1a64=0\n",
            "sss-cache-sum v1 len=x fnv1a64=0\n",
            "sss-cache-sum v1 len=9 fnv1a64=zz\n",
            "sss-cache-sum v1 len=9 fnv1a64=0 extra\n",
        ] {
            write_entry(&p, body).unwrap();
            std::fs::write(sum_path(&p), bad).unwrap();
            assert_eq!(
                corrupt_reason(check(&p)),
                "malformed checksum file",
                "{bad:?}"
            );
        }
        std::fs::remove_dir_all(&d).unwrap();
    }
}
