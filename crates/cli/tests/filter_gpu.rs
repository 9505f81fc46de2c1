//! `sss filter --gpu`: with the `gpu` feature and an adapter, the same exitance as the CPU
//! pass (`--jitter 0`) within f32 rounding, and the adapter named in the summary; without an
//! adapter (and without `SSS_REQUIRE_GPU=1`) or without the feature, one error line. Flags
//! the GPU pass cannot honour (jitter, the exact 2D kernel) are refused with one line.

mod common;
use common::{sss, stderr, stdout};
use std::path::PathBuf;

fn tmp_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("cli-{name}"));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn exitance(path: &std::path::Path) -> Vec<[f64; 3]> {
    let (_, _, layers) = sss_render::image::read_exr(path).unwrap();
    layers
        .into_iter()
        .find(|(n, _)| n == "exitance")
        .expect("layer exitance")
        .1
}

#[test]
fn filter_gpu_equals_the_cpu_pass_or_fails_with_one_line() {
    let dir = tmp_dir("filter-gpu");
    let scene = common::sphere_scene(&dir, "ball.toml", 40, 32);
    let (gb, sep) = (dir.join("g.exr"), dir.join("s.exr"));
    let o = sss(&[
        "render",
        scene.to_str().unwrap(),
        "--method",
        "separable",
        "--gbuffer",
        gb.to_str().unwrap(),
        "--out",
        sep.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let filter = |out: &std::path::Path, extra: &[&str]| {
        let mut args = vec![
            "filter",
            gb.to_str().unwrap(),
            "--preset",
            "skin1",
            "--units-per-mm",
            "0.1",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        sss(&args)
    };
    let one_line_error = |o: &std::process::Output, needle: &str| {
        assert!(!o.status.success());
        assert_eq!(o.status.code(), Some(2), "{}", stderr(o));
        let err = stderr(o);
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains(needle), "{err}");
    };
    let (cpu_path, gpu_path) = (dir.join("cpu.exr"), dir.join("gpu.exr"));
    let _ = std::fs::remove_file(&gpu_path);
    if cfg!(feature = "gpu") {
        // What the GPU pass cannot do is refused before any work.
        one_line_error(&filter(&gpu_path, &["--gpu"]), "--jitter 0");
        one_line_error(
            &filter(
                &gpu_path,
                &["--gpu", "--jitter", "0", "--kernel", "exact2d"],
            ),
            "separable kernels only",
        );
    } else {
        one_line_error(&filter(&gpu_path, &["--gpu"]), "`gpu` feature");
    }
    assert!(!gpu_path.exists());
    for kernel in ["preintegrated", "svd3"] {
        let o = filter(&cpu_path, &["--kernel", kernel, "--jitter", "0"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let _ = std::fs::remove_file(&gpu_path);
        let o = filter(&gpu_path, &["--kernel", kernel, "--jitter", "0", "--gpu"]);
        if !cfg!(feature = "gpu") {
            one_line_error(&o, "`gpu` feature");
            assert!(!gpu_path.exists());
            return;
        }
        if !o.status.success() {
            let err = stderr(&o);
            assert!(
                std::env::var("SSS_REQUIRE_GPU").as_deref() != Ok("1"),
                "SSS_REQUIRE_GPU=1 but: {err}"
            );
            one_line_error(&o, "no GPU adapter");
            eprintln!("skipped: {err}");
            return;
        }
        let text = stdout(&o);
        assert!(text.contains(" s on "), "the adapter is named: {text}");
        let (cpu, gpu) = (exitance(&cpu_path), exitance(&gpu_path));
        assert_eq!(cpu.len(), gpu.len());
        let peak: f64 = cpu.iter().flatten().fold(0.0, |m, v| m.max(v.abs()));
        let mut lit = 0;
        for (i, (a, b)) in cpu.iter().zip(&gpu).enumerate() {
            for c in 0..3 {
                assert!(
                    (a[c] - b[c]).abs() <= 1e-5 * a[c].abs() + 1e-6 * peak,
                    "{kernel}: pixel {i} channel {c}: cpu {} gpu {}",
                    a[c],
                    b[c]
                );
                lit += usize::from(a[c] > 0.0);
            }
        }
        assert!(lit > 100, "{kernel}: only {lit} lit values");
    }
}
