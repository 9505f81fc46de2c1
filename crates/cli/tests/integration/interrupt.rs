//! Interrupting the real `sss` binary (SIGINT, SIGTERM): exit status 130, no partial output and
//! no temporary file left next to the destination, whether the signal arrives during the
//! render or while the output is being written.

#![cfg(unix)]

use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::time::{Duration, Instant};

use crate::common;

/// A 2000×2000 sphere scene: long enough to interrupt (seconds of rendering, a 50 MB EXR that
/// takes a few hundred milliseconds to encode).
fn big_scene(dir: &Path) -> PathBuf {
    common::sphere_scene(dir, "big.toml", 2000, 2000)
}

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("sss-interrupt-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn start(args: &[&str]) -> Child {
    Command::new(env!("CARGO_BIN_EXE_sss"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start sss")
}

fn signal(child: &Child, sig: &str) {
    let st = Command::new("kill")
        .args([sig, &child.id().to_string()])
        .status()
        .expect("run kill");
    assert!(st.success(), "kill {sig} failed");
}

/// Waits at most `limit` for the child; kills it and fails the test past that.
fn wait_bounded(child: &mut Child, limit: Duration) -> (ExitStatus, String) {
    let t0 = Instant::now();
    loop {
        if let Some(st) = child.try_wait().unwrap() {
            let mut err = String::new();
            use std::io::Read;
            child
                .stderr
                .take()
                .unwrap()
                .read_to_string(&mut err)
                .unwrap();
            return (st, err);
        }
        if t0.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            panic!("sss did not exit within {limit:?} of the signal");
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

/// Names of the temporary files in `dir`.
fn temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp"))
        .collect()
}

#[test]
fn interrupt_during_the_render_exits_130_and_writes_nothing() {
    for sig in ["-INT", "-TERM"] {
        let dir = scratch(&sig[1..]);
        let scene = big_scene(&dir);
        let out = dir.join("out.exr");
        // Path tracing 2000×2000 at 64 samples per pixel on one thread takes minutes.
        let mut child = start(&[
            "render",
            scene.to_str().unwrap(),
            "--method",
            "pathtrace",
            "--spp",
            "64",
            "--threads",
            "1",
            "--out",
            out.to_str().unwrap(),
        ]);
        // Let it get past start-up (parsing, the output check, scene loading) into the render.
        std::thread::sleep(Duration::from_millis(500));
        assert!(
            child.try_wait().unwrap().is_none(),
            "sss ended before the signal"
        );
        signal(&child, sig);
        let (st, err) = wait_bounded(&mut child, Duration::from_secs(5));
        assert_eq!(st.code(), Some(130), "{sig}: {st:?}, stderr: {err}");
        assert!(
            err.contains("interrupted: removed 0 temporary files"),
            "{sig}: {err}"
        );
        assert!(!out.exists(), "{sig}: partial output written");
        assert!(
            temporaries(&dir).is_empty(),
            "{sig}: {:?}",
            temporaries(&dir)
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}

#[test]
fn interrupt_while_writing_removes_the_temporary_file() {
    let dir = scratch("write");
    let scene = big_scene(&dir);
    let out = dir.join("out.exr");
    // The separable method renders 2000×2000 in about 3 s on one thread, then encodes a 50 MB
    // EXR through a temporary file for a few hundred milliseconds.
    let mut child = start(&[
        "render",
        scene.to_str().unwrap(),
        "--method",
        "separable",
        "--threads",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    // Wait for the EXR's temporary file to have content (the empty probe of the output check
    // at start-up does not count), then interrupt.
    let t0 = Instant::now();
    let seen = loop {
        let tmp = std::fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .find(|e| {
                e.file_name().to_string_lossy().contains(".tmp")
                    && e.metadata().is_ok_and(|m| m.len() > 0)
            });
        if let Some(e) = tmp {
            break e.path();
        }
        if let Some(st) = child.try_wait().unwrap() {
            panic!("sss ended ({st:?}) before its temporary file was seen");
        }
        assert!(
            t0.elapsed() < Duration::from_secs(12),
            "no temporary file within 12 s"
        );
        std::thread::sleep(Duration::from_millis(1));
    };
    signal(&child, "-INT");
    let (st, err) = wait_bounded(&mut child, Duration::from_secs(5));
    assert_eq!(st.code(), Some(130), "{st:?}, stderr: {err}");
    assert!(
        err.contains("interrupted: removed 1 temporary file"),
        "{err}"
    );
    assert!(!seen.exists(), "{} left behind", seen.display());
    assert!(!out.exists(), "partial output written");
    assert!(temporaries(&dir).is_empty(), "{:?}", temporaries(&dir));
    std::fs::remove_dir_all(&dir).unwrap();
}
