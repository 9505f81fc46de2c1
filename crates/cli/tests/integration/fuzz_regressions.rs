//! Inputs found by `cargo xtask fuzz` or the coverage-guided fuzzer (`fuzz/`, see
//! docs/testing.md) that once made `sss` panic, kept as regression tests. Each runs the real
//! binary and checks its exit code and output (an input error: one `error:` line naming the
//! file, exit code 2, no output and no "internal error").

use std::path::PathBuf;
use std::process::{Command, Output};

use crate::common::sss;

fn tmp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "sss-cli-fuzz-regressions-{}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    dir
}

/// An uncompressed two-layer OpenEXR (848 bytes, written with the `exr` crate): layer
/// `irradiance` of 1x1 pixel and layer `surface` of 2x1 pixels (object id + 1 = 1, so both
/// surface pixels are translucent), as hex.
const MIXED_SIZES_EXR: &str = "\
    762f3101021000006368756e6b436f756e7400696e740004000000010000006368616e6e656c730063686c69\
    7374003700000042000200000000000000010000000100000047000200000000000000010000000100000052\
    000200000000000000010000000100000000636f6d7072657373696f6e00636f6d7072657373696f6e000100\
    0000006c696e654f72646572006c696e654f72646572000100000000646973706c617957696e646f7700626f\
    783269001000000000000000000000000100000000000000706978656c417370656374526174696f00666c6f\
    617400040000000000803f73637265656e57696e646f7743656e746572007632660008000000000000000000\
    000073637265656e57696e646f77576964746800666c6f617400040000000000803f6461746157696e646f77\
    00626f7832690010000000000000000000000000000000000000007479706500737472696e67000d00000073\
    63616e6c696e65696d6167656e616d6500737472696e67000a000000697272616469616e6365006368756e6b\
    436f756e7400696e740004000000010000006368616e6e656c730063686c6973740037000000420002000000\
    0000000001000000010000004700020000000000000001000000010000005200020000000000000001000000\
    0100000000636f6d7072657373696f6e00636f6d7072657373696f6e0001000000006c696e654f7264657200\
    6c696e654f72646572000100000000646973706c617957696e646f7700626f78326900100000000000000000\
    0000000100000000000000706978656c417370656374526174696f00666c6f617400040000000000803f7363\
    7265656e57696e646f7743656e746572007632660008000000000000000000000073637265656e57696e646f\
    77576964746800666c6f617400040000000000803f6461746157696e646f7700626f78326900100000000000\
    00000000000001000000000000007479706500737472696e67000d0000007363616e6c696e65696d6167656e\
    616d6500737472696e67000700000073757266616365000014030000000000002c0300000000000000000000\
    000000000c0000000000803f0000803f0000803f0100000000000000180000000000803f0000803f0000803f\
    0000803f0000803f00000040";

fn unhex(s: &str) -> Vec<u8> {
    let digits: Vec<u8> = s
        .bytes()
        .filter(u8::is_ascii_hexdigit)
        .map(|c| (c as char).to_digit(16).expect("hex digit") as u8)
        .collect();
    digits.chunks(2).map(|p| p[0] << 4 | p[1]).collect()
}

fn assert_input_error(o: &Output, file: &str) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    assert!(
        o.stdout.is_empty(),
        "stdout: {}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(!err.contains("internal error"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.starts_with("error: ") && err.contains(file), "{err}");
    assert!(err.contains("same size"), "{err}");
}

/// `cargo xtask fuzz --target exr --seed 2` (15 of the first 1000 iterations, e.g. 689): a
/// G-buffer whose layers differ in size made `sss filter` index the smaller layer out of
/// bounds ("index out of bounds: the len is 1 but the index is 1 at
/// crates/cli/src/commands/filter.rs:82"), and `sss diff` compare a layer against the wrong
/// size. `read_exr` now refuses the file.
#[test]
fn filter_and_diff_refuse_layers_of_different_sizes() {
    let dir = tmp_dir("mixed");
    let input = dir.join("mixed.exr");
    let bytes = unhex(MIXED_SIZES_EXR);
    assert_eq!(bytes.len(), 848);
    std::fs::write(&input, bytes).unwrap();
    let input_s = input.to_str().unwrap();
    let out = dir.join("out.exr");
    let o = sss(&[
        "filter",
        input_s,
        "--preset",
        "skin1",
        "--units-per-mm",
        "0.05",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_input_error(&o, input_s);
    assert!(!out.exists());
    let o = sss(&["diff", input_s, input_s, "--layer", "irradiance"]);
    assert_input_error(&o, input_s);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A 4x3 OpenEXR of B44-compressed half channels `A`, `B`, `G`, `R` and `surface.{B,G,R}`
/// whose blocks make exr's B44 decoder wrap its u32 arithmetic (552 bytes, found by the `exr`
/// target of `fuzz/` and minimised by libFuzzer), as hex.
const B44_WRAPPING_EXR: &str = "\
    762f3101020000006368616e6e656c730063686c697374009700000041000100000000000000010000000100\
    0000420001000000000000000100000001000000470001000000000000000100000001000000520001000000\
    000000000100000001000000737572666163652e420001000000000000000100000001000000737572666163\
    652e470001000000000000000100000001000000737572666163652e52000100000000000000010000000100\
    000000636f6d7072657373696f6e00636f6d7072657373696f6e0001000000066461746157696e646f770062\
    6f783269001000000000000000000000000300000002000000646973706c617957696e646f7700626f783269\
    0010000000000000005400000003000000020000006c696e654f72646572006c696e654f7264657200010000\
    0000706978656c4173706563745261ffffffff666c6f617400040000000000803f73637265656e57696e646f\
    7743656e746572007632660008000000000000000000000073637265656e57696e646f77576964746800666c\
    6f617400040000000000803f7479706500737472696e67000d0000007363616e6c696e65696d61676500be01\
    00000000000000000000620000007f8b27b8a0de18208a0861861820ab801f69e0aa38619a18a28e2861a7ff\
    ffff1f451fda20c238619a28a228617f8b27b8a0de18208a08618618201f69e0aa38619a18a28e2861a745da\
    20c238619a28a29628617f8b27b8a0de18208a0861861820";

/// `fuzz/run.sh` (target `exr`): exr's B44 decoder computes `s[0] + d - bias` in u32 and
/// keeps the low 16 bits, wrapping on purpose as OpenEXR's C code does. A debug build checked
/// the subtraction, panicked in exr's decompressor thread and aborted `sss` (exit code 134);
/// the root Cargo.toml turns exr's overflow checks off in debug builds, so every build reads
/// the file as a release build does. (A release build of this test passes either way; the
/// debug one, `cargo test -p sss-cli --test integration fuzz_regressions`, fails without.)
#[test]
fn b44_blocks_that_wrap_read_as_in_a_release_build() {
    let dir = tmp_dir("b44");
    let input = dir.join("b44.exr");
    let bytes = unhex(B44_WRAPPING_EXR);
    assert_eq!(bytes.len(), 552);
    std::fs::write(&input, bytes).unwrap();
    let input_s = input.to_str().unwrap();
    let o = sss(&["diff", input_s, input_s, "--layer", "surface"]);
    let (out, err) = (
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr),
    );
    assert_eq!(o.status.code(), Some(0), "stderr: {err}");
    assert!(out.lines().next() == Some("pixels 12"), "{out}");
    assert!(out.contains("rmse 0.000000e0"), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `sss` with `args`, killing it after `limit`; `None` when it did not finish in time.
fn sss_within(args: &[&str], limit: std::time::Duration) -> Option<Output> {
    let mut child = Command::new(env!("CARGO_BIN_EXE_sss"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run sss");
    let t0 = std::time::Instant::now();
    while child.try_wait().expect("wait for sss").is_none() {
        if t0.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            return None;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    Some(child.wait_with_output().expect("collect sss output"))
}

/// `cargo xtask fuzz --seed 1 --seconds 60` (target `cli`, iteration 2374): a log-scale
/// profile plot with `--r-max 5e-324` never finished (the log x axis of one subnormal radius
/// started at 10^-324 = 0 and plotters' tick generation looped forever). The plot is now
/// written, the CSV printed.
#[test]
fn profile_plot_with_a_subnormal_r_max_finishes() {
    let dir = tmp_dir("subnormal");
    let plot = dir.join("p.svg");
    let o = sss_within(
        &[
            "profile",
            "--model",
            "pbd",
            "--sigma-a",
            "0.01,0.02,0.03",
            "--sigma-s",
            "2,2,2",
            "--r-max",
            "5e-324",
            "--steps",
            "8",
            "--log",
            "--plot",
            plot.to_str().unwrap(),
        ],
        std::time::Duration::from_secs(60),
    )
    .expect("sss profile --r-max 5e-324 --log --plot did not finish within 60 s");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(String::from_utf8_lossy(&o.stdout).starts_with("# total_diffuse_reflectance="));
    assert!(plot.metadata().is_ok_and(|m| m.len() > 0));
    let _ = std::fs::remove_dir_all(&dir);
}
