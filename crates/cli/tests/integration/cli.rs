//! End-to-end tests of the `sss` binary: output format, agreement with the library, error
//! handling and plots.

use sss_bssrdf::{Medium, ModelKind, make_model, presets::PRESETS};
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common;
use crate::common::{sss, stderr, stdout};

fn ok(args: &[&str]) -> String {
    let o = sss(args);
    assert!(o.status.success(), "sss {args:?} failed: {}", stderr(&o));
    stdout(&o)
}

/// A parsed profile CSV: the comment line's totals, the header and the numeric rows.
struct Csv {
    total: [f64; 3],
    header: String,
    rows: Vec<Vec<f64>>,
}

fn parse_csv(text: &str) -> Csv {
    let mut lines = text.lines();
    let comment = lines.next().expect("comment line");
    let totals = comment
        .strip_prefix("# total_diffuse_reflectance=")
        .unwrap_or_else(|| panic!("bad comment line {comment:?}"));
    let t: Vec<f64> = totals.split(',').map(|v| v.parse().unwrap()).collect();
    assert_eq!(t.len(), 3);
    let header = lines.next().expect("header").to_string();
    let rows: Vec<Vec<f64>> = lines
        .map(|l| {
            assert!(!l.starts_with('#'), "exactly one comment line");
            l.split(',')
                .map(|v| {
                    let x: f64 = v.parse().unwrap_or_else(|_| panic!("bad number {v:?}"));
                    assert!(x.is_finite());
                    x
                })
                .collect()
        })
        .collect();
    Csv {
        total: [t[0], t[1], t[2]],
        header,
        rows,
    }
}

fn tmp_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("cli-{name}"));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn rel_close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol * a.abs().max(b.abs()) || (a - b).abs() < 1e-300
}

#[test]
fn profile_output_has_one_comment_line_and_the_header() {
    for model in ModelKind::ALL {
        let out = ok(&[
            "profile",
            "--model",
            model.name(),
            "--preset",
            "skin1",
            "--r-max",
            "4",
            "--steps",
            "7",
        ]);
        let lines: Vec<&str> = out.lines().collect();
        assert_eq!(lines.len(), 9, "{model}: {out}");
        assert!(lines[0].starts_with("# total_diffuse_reflectance="));
        assert_eq!(lines.iter().filter(|l| l.starts_with('#')).count(), 1);
        assert_eq!(lines[1], "r_mm,rd_r,rd_g,rd_b");
        let csv = parse_csv(&out);
        assert!(csv.rows.iter().all(|r| r.len() == 4));
        // Linear radii r_max/N .. r_max.
        assert!(rel_close(csv.rows[0][0], 4.0 / 7.0, 1e-15));
        assert_eq!(csv.rows[6][0], 4.0);
    }
}

#[test]
fn profile_values_equal_the_library() {
    let medium = Medium::preset("marble").unwrap().with_eta(1.4).unwrap();
    for model in ModelKind::ALL {
        let lib = make_model(model, &medium);
        for log in [false, true] {
            let mut args = vec![
                "profile",
                "--model",
                model.name(),
                "--preset",
                "marble",
                "--eta",
                "1.4",
                "--r-max",
                "30",
                "--steps",
                "25",
            ];
            if log {
                args.push("--log");
            }
            let csv = parse_csv(&ok(&args));
            assert_eq!(csv.rows.len(), 25);
            for ch in 0..3 {
                assert!(
                    rel_close(csv.total[ch], lib.total_diffuse_reflectance(ch), 1e-9),
                    "{model} total {ch}"
                );
            }
            for row in &csv.rows {
                for ch in 0..3 {
                    let want = lib.rd(ch, row[0]);
                    assert!(
                        rel_close(row[1 + ch], want, 1e-9),
                        "{model} r {} ch {ch}: {} vs {want}",
                        row[0],
                        row[1 + ch]
                    );
                }
            }
            if log {
                assert!(rel_close(csv.rows[0][0], 30.0e-4, 1e-12));
                assert!(rel_close(csv.rows[24][0], 30.0, 1e-12));
            }
        }
    }
}

#[test]
fn profile_from_coefficients_equals_the_library() {
    let medium = Medium::new([0.05, 0.1, 0.3], [2.0, 1.5, 1.0], 0.3, 1.2).unwrap();
    for model in [ModelKind::StandardDipole, ModelKind::PhotonBeamDiffusion] {
        let lib = make_model(model, &medium);
        let csv = parse_csv(&ok(&[
            "profile",
            "--model",
            model.name(),
            "--sigma-a",
            "0.05,0.1,0.3",
            "--sigma-s",
            "2,1.5,1",
            "--g",
            "0.3",
            "--eta",
            "1.2",
            "--r-max",
            "5",
            "--steps",
            "10",
        ]));
        for row in &csv.rows {
            for ch in 0..3 {
                assert!(rel_close(row[1 + ch], lib.rd(ch, row[0]), 1e-9));
            }
        }
    }
}

#[test]
fn standard_dipole_profile_integrates_to_its_total() {
    // Trapezoid rule over 2πr Rd(r) from r = 0 (where the integrand is 0) to 60 mm, far past
    // where skin1's profile has decayed (σ_tr ≥ 0.27/mm).
    let csv = parse_csv(&ok(&[
        "profile",
        "--model",
        "standard-dipole",
        "--preset",
        "skin1",
        "--r-max",
        "60",
        "--steps",
        "60000",
    ]));
    for ch in 0..3 {
        let mut prev = (0.0, 0.0);
        let mut integral = 0.0;
        for row in &csv.rows {
            let f = 2.0 * std::f64::consts::PI * row[0] * row[1 + ch];
            integral += 0.5 * (f + prev.1) * (row[0] - prev.0);
            prev = (row[0], f);
        }
        let total = csv.total[ch];
        assert!(
            rel_close(integral, total, 2e-3),
            "channel {ch}: trapezoid {integral} vs printed total {total}"
        );
    }
}

#[test]
fn monte_carlo_profile_has_standard_errors_and_is_seeded() {
    let args = [
        "profile",
        "--model",
        "monte-carlo",
        "--preset",
        "skin1",
        "--r-max",
        "8",
        "--steps",
        "16",
        "--photons",
        "20000",
        "--seed",
        "7",
    ];
    let a = ok(&args);
    let csv = parse_csv(&a);
    assert_eq!(csv.header, "r_mm,rd_r,rd_g,rd_b,se_r,se_g,se_b");
    assert_eq!(csv.rows.len(), 16);
    // Bin centres of 16 bins over [0, 8].
    assert!(rel_close(csv.rows[0][0], 0.25, 1e-12));
    assert!(rel_close(csv.rows[15][0], 7.75, 1e-12));
    for row in &csv.rows {
        assert_eq!(row.len(), 7);
        assert!(row[1..].iter().all(|v| *v >= 0.0));
    }
    assert!(csv.total.iter().all(|t| *t > 0.0 && *t < 1.0));
    assert_eq!(a, ok(&args), "same seed, same output");
}

#[test]
fn bad_input_fails_with_one_line_and_no_output() {
    let dir = tmp_dir("bad");
    let unwritable = dir.join("missing-dir").join("p.png");
    let unwritable = unwritable.to_str().unwrap();
    let base = ["profile", "--model", "better-dipole"];
    let cases: Vec<Vec<&str>> = vec![
        vec![
            "profile", "--model", "nope", "--preset", "skin1", "--r-max", "1", "--steps", "3",
        ],
        [
            &base[..],
            &["--preset", "nope", "--r-max", "1", "--steps", "3"],
        ]
        .concat(),
        [
            &base[..],
            &[
                "--sigma-a",
                "-1,1,1",
                "--sigma-s",
                "1,1,1",
                "--r-max",
                "1",
                "--steps",
                "3",
            ],
        ]
        .concat(),
        [
            &base[..],
            &[
                "--sigma-a",
                "NaN,1,1",
                "--sigma-s",
                "1,1,1",
                "--r-max",
                "1",
                "--steps",
                "3",
            ],
        ]
        .concat(),
        [
            &base[..],
            &[
                "--sigma-a",
                "1,1,1",
                "--sigma-s",
                "1,nan,1",
                "--r-max",
                "1",
                "--steps",
                "3",
            ],
        ]
        .concat(),
        [
            &base[..],
            &[
                "--sigma-a",
                "1,1",
                "--sigma-s",
                "1,1,1",
                "--r-max",
                "1",
                "--steps",
                "3",
            ],
        ]
        .concat(),
        [
            &base[..],
            &[
                "--sigma-a",
                "1;1;1",
                "--sigma-s",
                "1,1,1",
                "--r-max",
                "1",
                "--steps",
                "3",
            ],
        ]
        .concat(),
        [
            &base[..],
            &["--preset", "skin1", "--r-max", "0", "--steps", "3"],
        ]
        .concat(),
        [
            &base[..],
            &["--preset", "skin1", "--r-max", "-2", "--steps", "3"],
        ]
        .concat(),
        [
            &base[..],
            &["--preset", "skin1", "--r-max", "nan", "--steps", "3"],
        ]
        .concat(),
        [
            &base[..],
            &["--preset", "skin1", "--r-max", "1", "--steps", "0"],
        ]
        .concat(),
        [
            &base[..],
            &[
                "--preset", "skin1", "--r-max", "1", "--steps", "3", "--plot", unwritable,
            ],
        ]
        .concat(),
        [
            &base[..],
            &[
                "--preset", "skin1", "--r-max", "1", "--steps", "3", "--plot", "p.pdf",
            ],
        ]
        .concat(),
        [
            &base[..],
            &[
                "--preset",
                "skin1",
                "--sigma-a",
                "1,1,1",
                "--sigma-s",
                "1,1,1",
                "--r-max",
                "1",
                "--steps",
                "3",
            ],
        ]
        .concat(),
        [&base[..], &["--r-max", "1", "--steps", "3"]].concat(),
        [
            &base[..],
            &[
                "--preset", "skin1", "--eta", "0", "--r-max", "1", "--steps", "3",
            ],
        ]
        .concat(),
        [
            &base[..],
            &[
                "--sigma-a",
                "1,1,1",
                "--sigma-s",
                "1,1,1",
                "--g",
                "1",
                "--r-max",
                "1",
                "--steps",
                "3",
            ],
        ]
        .concat(),
        vec![
            "profile",
            "--model",
            "monte-carlo",
            "--preset",
            "skin1",
            "--r-max",
            "1",
            "--steps",
            "3",
            "--photons",
            "0",
        ],
        vec![
            "profile",
            "--model",
            "monte-carlo",
            "--preset",
            "skin1",
            "--r-max",
            "1",
            "--steps",
            "3",
            "--log",
        ],
        vec![],
        vec!["frobnicate"],
    ];
    for args in &cases {
        let o = sss(args);
        let err = stderr(&o);
        assert!(!o.status.success(), "{args:?} succeeded");
        assert_ne!(o.status.code(), Some(101), "{args:?} panicked: {err}");
        assert!(o.stdout.is_empty(), "{args:?} printed {:?}", stdout(&o));
        assert_eq!(err.lines().count(), 1, "{args:?}: {err:?}");
        assert!(err.starts_with("error: "), "{args:?}: {err:?}");
    }
    assert!(!dir.join("missing-dir").exists());
}

#[test]
fn plot_writes_png_and_svg() {
    let dir = tmp_dir("plot");
    for (model, file) in [
        ("better-dipole", "profile.png"),
        ("pbd", "profile.svg"),
        ("monte-carlo", "mc.png"),
    ] {
        let path = dir.join(file);
        let _ = std::fs::remove_file(&path);
        let out = ok(&[
            "profile",
            "--model",
            model,
            "--preset",
            "skin2",
            "--r-max",
            "10",
            "--steps",
            "40",
            "--photons",
            "5000",
            "--plot",
            path.to_str().unwrap(),
        ]);
        assert!(out.starts_with("# total_diffuse_reflectance="));
        let bytes = std::fs::read(&path).unwrap();
        assert!(bytes.len() > 1000, "{file}: {} bytes", bytes.len());
        if file.ends_with(".png") {
            assert_eq!(&bytes[1..4], b"PNG");
        } else {
            assert!(String::from_utf8_lossy(&bytes).contains("<svg"));
        }
    }
    // No temporary files left behind.
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        assert!(!name.starts_with('.'), "left over: {name}");
    }
}

#[test]
fn presets_lists_all_twelve() {
    let table = ok(&["presets"]);
    assert_eq!(table.lines().count(), 13);
    let csv = ok(&["presets", "--csv"]);
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines.len(), 13);
    assert!(lines[0].starts_with("name,sigma_s_reduced_r,"));
    for p in &PRESETS {
        assert!(
            table
                .lines()
                .any(|l| l.split_whitespace().next() == Some(p.name))
        );
        let row = lines
            .iter()
            .find(|l| l.split(',').next() == Some(p.name))
            .unwrap_or_else(|| panic!("{} missing", p.name));
        let v: Vec<f64> = row.split(',').skip(1).map(|x| x.parse().unwrap()).collect();
        assert_eq!(v.len(), 10);
        assert_eq!(&v[0..3], &p.sigma_s_reduced);
        assert_eq!(&v[3..6], &p.sigma_a);
        assert_eq!(v[6], 1.3);
        assert_eq!(&v[7..10], &p.published_rd);
    }
}

#[test]
fn help_and_version_succeed() {
    let h = ok(&["--help"]);
    assert!(h.contains("profile") && h.contains("presets"));
    let h = ok(&["profile", "--help"]);
    assert!(h.contains("monte-carlo") && h.contains("--sigma-a"));
    assert!(ok(&["--version"]).starts_with("sss "));
}

/// A tiny scene file for render tests: a sphere under a point light, 12×10 pixels.
fn tiny_scene(dir: &Path) -> PathBuf {
    common::sphere_scene(dir, "tiny.toml", 12, 10)
}

#[test]
fn render_writes_exr_and_png_and_reports_stages() {
    let dir = tmp_dir("render");
    let scene = tiny_scene(&dir);
    let exr = dir.join("a.exr");
    let png = dir.join("a.png");
    let text = ok(&[
        "render",
        scene.to_str().unwrap(),
        "--method",
        "pathtrace",
        "--spp",
        "4",
        "--out",
        exr.to_str().unwrap(),
        "--png",
        png.to_str().unwrap(),
        "--threads",
        "2",
    ]);
    for stage in ["bvh", "gbuffer", "shading", "total"] {
        assert!(
            text.lines().any(|l| l.starts_with(stage)),
            "no {stage} line in\n{text}"
        );
    }
    let (w, h, layers) = sss_render::image::read_exr(&exr).unwrap();
    assert_eq!((w, h), (12, 10));
    let names: Vec<&str> = layers.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names.len(), 3, "{names:?}");
    for n in ["total", "subsurface", "std_error"] {
        assert!(names.contains(&n), "{names:?}");
    }
    let sub = &layers.iter().find(|(n, _)| n == "subsurface").unwrap().1;
    assert!(sub.iter().flatten().any(|v| *v > 0.0));
    assert!(sub.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    // No temporary files left behind.
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");

    // The same seed gives the same bits; the exact reference differs from a noisy render and
    // `sss diff` measures it and draws the error map.
    let exr2 = dir.join("b.exr");
    ok(&[
        "render",
        scene.to_str().unwrap(),
        "--method",
        "pathtrace",
        "--spp",
        "4",
        "--out",
        exr2.to_str().unwrap(),
        "--threads",
        "1",
    ]);
    let (_, _, again) = sss_render::image::read_exr(&exr2).unwrap();
    assert_eq!(
        layers, again,
        "same seed, different thread count, different image"
    );
    let reference = dir.join("ref.exr");
    ok(&[
        "render",
        scene.to_str().unwrap(),
        "--out",
        reference.to_str().unwrap(),
    ]);
    let err_png = dir.join("err.png");
    let diff = ok(&[
        "diff",
        exr.to_str().unwrap(),
        reference.to_str().unwrap(),
        "--png",
        err_png.to_str().unwrap(),
    ]);
    let rmse: f64 = diff
        .lines()
        .find_map(|l| l.strip_prefix("rmse "))
        .unwrap()
        .parse()
        .unwrap();
    assert!(rmse > 0.0 && rmse.is_finite(), "{diff}");
    let same = ok(&[
        "diff",
        reference.to_str().unwrap(),
        reference.to_str().unwrap(),
    ]);
    assert!(same.contains("rmse 0.000000e0"), "{same}");
    assert!(same.contains("\nflip 0.000000\n"), "{same}");
    assert!(std::fs::metadata(&err_png).unwrap().len() > 100);
    // HDR-FLIP (checked against NVIDIA's flip-evaluator in sss-render's tests): in (0, 1) for
    // a 4-spp render, and the map of it drawn.
    let flip_png = dir.join("flip.png");
    let with_map = ok(&[
        "diff",
        exr.to_str().unwrap(),
        reference.to_str().unwrap(),
        "--flip-map",
        flip_png.to_str().unwrap(),
    ]);
    assert_eq!(with_map, diff, "the map changes no figure");
    let flip: f64 = diff
        .lines()
        .find_map(|l| l.strip_prefix("flip "))
        .unwrap()
        .parse()
        .unwrap();
    assert!(flip > 0.0 && flip < 1.0, "{diff}");
    assert!(std::fs::metadata(&flip_png).unwrap().len() > 100);

    // The map's range: pixels beyond it are drawn in the over-range green (besides its
    // 20 × 14 swatch by the colour bar); a range above every error leaves only the swatch.
    let green = |range: &str, log: bool| -> usize {
        let mut args = vec![
            "diff",
            exr.to_str().unwrap(),
            reference.to_str().unwrap(),
            "--png",
            err_png.to_str().unwrap(),
            "--range",
            range,
        ];
        if log {
            args.push("--log");
        }
        ok(&args);
        let decoder = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(&err_png).unwrap(),
        ));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        let step = info.color_type.samples();
        buf[..info.buffer_size()]
            .chunks_exact(step)
            .filter(|p| p[..3] == sss_plot::OVER_RANGE)
            .count()
    };
    let swatch = 20 * 14;
    assert_eq!(green("1e9", false), swatch);
    assert_eq!(green("1e9", true), swatch);
    let over = green("1e-9", false);
    assert!(over > swatch + 1000, "{over} green pixels");
    let e = sss(&[
        "diff",
        exr.to_str().unwrap(),
        reference.to_str().unwrap(),
        "--range",
        "0",
    ]);
    assert!(!e.status.success());
    assert!(String::from_utf8_lossy(&e.stderr).contains("--range must be"));

    // Another renderer's EXR: its plain R,G,B (`beauty`) against our `subsurface`, each side
    // naming its layer; the same figures as against our own file.
    let (rw, rh, ref_layers) = sss_render::image::read_exr(&reference).unwrap();
    let sub = &ref_layers
        .iter()
        .find(|(n, _)| n == "subsurface")
        .unwrap()
        .1;
    let theirs = dir.join("theirs.exr");
    sss_render::image::write_exr(&theirs, rw, rh, &[("beauty", sub)]).unwrap();
    let (a, t) = (exr.to_str().unwrap(), theirs.to_str().unwrap());
    let o = sss(&["diff", a, t]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(
        err.contains("no layer `subsurface`") && err.contains("--reference-layer"),
        "{err}"
    );
    let peer = ok(&["diff", a, t, "--reference-layer", "beauty"]);
    assert_eq!(peer, diff, "the same figures against the same pixels");
}

/// `--out` holds the method's own layers too, as its help says: dual-tree's sampling rate
/// (positive where the sphere is seen) and pixel clusters.
#[test]
fn render_out_holds_the_methods_layers() {
    let dir = tmp_dir("render-layers");
    let scene = tiny_scene(&dir);
    let exr = dir.join("dt.exr");
    ok(&[
        "render",
        scene.to_str().unwrap(),
        "--method",
        "dual-tree",
        "--out",
        exr.to_str().unwrap(),
    ]);
    let (_, _, layers) = sss_render::image::read_exr(&exr).unwrap();
    let mut names: Vec<&str> = layers.iter().map(|(n, _)| n.as_str()).collect();
    names.sort();
    assert_eq!(
        names,
        ["pixel_clusters", "sampling_rate", "subsurface", "total"],
        "{names:?}"
    );
    let rate = &layers.iter().find(|(n, _)| n == "sampling_rate").unwrap().1;
    assert!(rate.iter().any(|p| p[0] > 0.0), "no sampling rate anywhere");
    assert!(rate.iter().flatten().all(|v| v.is_finite() && *v >= 0.0));

    // The beauty's alpha: the silhouette (1 on the sphere's centre, 0 in the corners).
    let alpha = sss_render::image::read_exr_alpha(&exr)
        .unwrap()
        .expect("no alpha channel");
    let (w, h, _) = sss_render::image::read_exr(&exr).unwrap();
    assert_eq!(alpha.len(), (w * h) as usize);
    assert!(alpha.iter().all(|a| (0.0..=1.0).contains(a)), "{alpha:?}");
    assert_eq!(alpha[(h / 2 * w + w / 2) as usize], 1.0, "{alpha:?}");
    assert_eq!(alpha[0], 0.0, "{alpha:?}");

    // The header says how the image was made.
    let made = sss_render::image::read_exr_attributes(&exr).unwrap();
    let get = |k: &str| {
        made.iter()
            .find(|(n, _)| n == k)
            .map(|(_, v)| v.clone())
            .unwrap_or_else(|| panic!("no {k} in {made:?}"))
    };
    assert_eq!(get("sss/method"), "dual-tree");
    assert_eq!(get("sss/seed"), "1");
    assert_eq!(get("sss/scene"), scene.to_str().unwrap());
    assert_eq!(get("sss/version"), env!("CARGO_PKG_VERSION"));
    assert!(get("sss/settings").contains("ρ = 0.75"), "{made:?}");
    assert!(get("sss/models").contains(':'), "{made:?}");
    assert!(get("sss/seconds").parse::<f64>().unwrap() > 0.0);

    // The camera's resolution and samples overridden from the command line.
    let small = dir.join("small.exr");
    ok(&[
        "render",
        scene.to_str().unwrap(),
        "--resolution",
        "6x4",
        "--pixel-samples",
        "3",
        "--out",
        small.to_str().unwrap(),
    ]);
    let (w, h, _) = sss_render::image::read_exr(&small).unwrap();
    assert_eq!((w, h), (6, 4));
    let made = sss_render::image::read_exr_attributes(&small).unwrap();
    assert!(
        made.contains(&("sss/pixel_samples".to_string(), "3".to_string())),
        "{made:?}"
    );
}

#[test]
fn render_bad_input_fails_with_one_line() {
    let dir = tmp_dir("render-bad");
    let scene = tiny_scene(&dir);
    let scene = scene.to_str().unwrap();
    let bad_toml = dir.join("bad.toml");
    std::fs::write(&bad_toml, "[camera]\nposition = [0, 0]\n").unwrap();
    let missing_dir = dir.join("no-such-dir").join("x.exr");
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["render", "no-such-scene"], "no-such-scene"),
        (vec!["render", bad_toml.to_str().unwrap()], "bad.toml"),
        (vec!["render", scene, "--out", "x.png"], ".exr"),
        (vec!["render", scene, "--png", "x.exr"], ".png"),
        (
            vec!["render", scene, "--out", missing_dir.to_str().unwrap()],
            "no-such-dir",
        ),
        (
            vec!["render", scene, "--spp", "0", "--method", "pathtrace"],
            "--spp",
        ),
        (vec!["render", scene, "--spacing", "-1"], "--spacing"),
        (vec!["render", scene, "--threads", "0"], "--threads"),
        (vec!["render", scene, "--resolution", "0x5"], "--resolution"),
        (vec!["render", scene, "--resolution", "640"], "WIDTHxHEIGHT"),
        (
            vec!["render", scene, "--pixel-samples", "0"],
            "--pixel-samples",
        ),
        (vec!["render", scene, "--method", "magic"], "magic"),
        (vec!["diff", "nope-a.exr", "nope-b.exr"], "nope-a.exr"),
        // The old --eps, split into two quantities, names the one the method takes.
        (
            vec!["render", scene, "--method", "dual-tree", "--eps", "0.1"],
            "method dual-tree takes --solid-angle",
        ),
        (
            vec!["render", scene, "--method", "eelc", "--eps", "0.1"],
            "method eelc takes --rel-error",
        ),
    ];
    for (args, needle) in cases {
        let o = sss(&args);
        assert!(!o.status.success(), "{args:?} succeeded");
        let err = stderr(&o);
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("error: "), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: `{needle}` not in {err}");
        assert!(stdout(&o).is_empty(), "{args:?}");
    }
    assert!(!missing_dir.exists());
}

/// What a new user mistypes gets an error that says what to do: a scene name that is neither
/// a file nor a built-in scene lists the built-in scenes; a missing mesh names `--mesh-dir`
/// (not a Rust API) and each directory searched once.
#[test]
fn missing_scenes_and_meshes_say_what_to_do() {
    let o = sss(&["render", "bunnyy"]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    for w in [
        "bunnyy",
        "built-in scene",
        "sphere, toad, picnic, backlit, slab, bunny",
    ] {
        assert!(err.contains(w), "`{w}` not in {err}");
    }

    let dir = tmp_dir("missing-mesh");
    let scene = dir.join("mesh.toml");
    std::fs::write(
        &scene,
        "[camera]\nposition = [0, 0, 4]\ntarget = [0, 0, 0]\nfov = 35\nresolution = [8, 8]\n\n\
         [[lights]]\ntype = \"point\"\nposition = [0, 4, 4]\nintensity = 10\n\n\
         [materials.skin]\ntype = \"translucent\"\npreset = \"skin1\"\nunits_per_mm = 0.1\n\n\
         [[objects]]\nmaterial = \"skin\"\nshape = \"mesh\"\nfile = \"missing.obj\"\n",
    )
    .unwrap();
    let d = dir.to_str().unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_sss"))
        .args(["render", scene.to_str().unwrap(), "--mesh-dir", d])
        .env_remove("SSS_MESH_DIR")
        .output()
        .unwrap();
    assert!(!o.status.success());
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    for w in ["missing.obj", "--mesh-dir DIR", "SSS_MESH_DIR"] {
        assert!(err.contains(w), "`{w}` not in {err}");
    }
    assert!(!err.contains("LoadOptions"), "{err}");
    // The scene's directory and the mesh directory are the same: listed once.
    assert_eq!(
        err.matches(d).count(),
        2,
        "the scene file and one directory: {err}"
    );
}

/// `sss kernel` JSON: per-channel weight sums equal the model's total diffuse reflectance (or 1
/// with --normalize), for every rank-1 method; multi-term kernels export terms whose products
/// sum to it.
#[test]
fn kernel_export_conserves_energy() {
    let model = make_model(ModelKind::BetterDipole, &Medium::preset("skin1").unwrap());
    let total: Vec<f64> = (0..3).map(|c| model.total_diffuse_reflectance(c)).collect();
    let sums = |taps: &serde_json::Value| -> Vec<f64> {
        let mut s = vec![0.0; 3];
        for t in taps.as_array().unwrap() {
            for (c, v) in t["weights"].as_array().unwrap().iter().enumerate() {
                s[c] += v.as_f64().unwrap();
            }
        }
        s
    };
    for method in ["preintegrated", "svd1", "artist", "guided", "gaussians1"] {
        for normalize in [false, true] {
            let mut args = vec![
                "kernel", "--preset", "skin1", "--method", method, "--taps", "9",
            ];
            if normalize {
                args.push("--normalize");
            }
            let v: serde_json::Value = serde_json::from_str(&ok(&args)).unwrap();
            assert_eq!(v["normalized"].as_bool(), Some(normalize));
            assert_eq!(v["taps"].as_array().unwrap().len(), 9, "{method}");
            let s = sums(&v["taps"]);
            for c in 0..3 {
                let want = if normalize { 1.0 } else { total[c] };
                assert!(
                    rel_close(s[c], want, 1e-9),
                    "{method} ch {c}: {} vs {want}",
                    s[c]
                );
            }
        }
    }
    for method in ["svd3", "gaussians6"] {
        let v: serde_json::Value =
            serde_json::from_str(&ok(&["kernel", "--preset", "skin1", "--method", method]))
                .unwrap();
        let terms = v["terms"].as_array().unwrap();
        assert!(terms.len() > 1, "{method}");
        let mut e = [0.0; 3];
        for t in terms {
            let (h, vv) = (sums(&t["horizontal"]), sums(&t["vertical"]));
            for c in 0..3 {
                e[c] += h[c] * vv[c];
            }
        }
        for c in 0..3 {
            assert!(
                rel_close(e[c], total[c], 1e-9),
                "{method} ch {c}: {} vs {}",
                e[c],
                total[c]
            );
        }
    }
    // GLSL/HLSL: one float4 per tap, centre first; CSV one row per tap.
    let glsl = ok(&[
        "kernel", "--preset", "marble", "--format", "glsl", "--taps", "7",
    ]);
    assert!(glsl.contains("vec4 sssKernel[7]"), "{glsl}");
    assert_eq!(glsl.matches("vec4(").count(), 7);
    assert!(glsl.contains(", 0.0)"), "centre tap first: {glsl}");
    let hlsl = ok(&[
        "kernel", "--preset", "marble", "--format", "hlsl", "--taps", "5",
    ]);
    assert!(hlsl.contains("static const float4 sssKernel[5]"), "{hlsl}");
    // WGSL: the same taps as GLSL, each array with its tap count (naga parses and validates
    // both in sss-separable's tests/shader_export.rs).
    for method in ["preintegrated", "svd3"] {
        let export = |format: &str| {
            ok(&[
                "kernel",
                "--preset",
                "marble",
                "--method",
                method,
                "--format",
                format,
                "--taps",
                "7",
                "--normalize",
            ])
        };
        let (glsl, wgsl) = (export("glsl"), export("wgsl"));
        let taps = |text: &str, ty: &str| -> Vec<String> {
            text.lines()
                .filter_map(|l| l.trim().strip_prefix(ty).map(str::to_string))
                .collect()
        };
        let arrays = if method == "svd3" { 6 } else { 1 };
        assert_eq!(taps(&glsl, "vec4(").len(), 7 * arrays, "{glsl}");
        assert_eq!(taps(&glsl, "vec4("), taps(&wgsl, "vec4<f32>("), "{wgsl}");
        assert_eq!(wgsl.matches(": array<vec4<f32>, 7> =").count(), arrays);
        assert_eq!(wgsl.matches("Taps: u32 = 7u;").count(), arrays);
        assert_eq!(wgsl.lines().next(), glsl.lines().next());
    }
    let csv = ok(&[
        "kernel", "--preset", "marble", "--format", "csv", "--taps", "5",
    ]);
    assert_eq!(csv.lines().count(), 6, "{csv}");
    assert!(csv.starts_with("term,direction,offset_mm,weight_r,weight_g,weight_b"));
}

#[test]
fn kernel_bad_input_fails_with_one_line() {
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["kernel", "--preset", "nope"], "nope"),
        (vec!["kernel", "--preset", "skin1", "--taps", "0"], "--taps"),
        (
            vec!["kernel", "--preset", "skin1", "--method", "exact2d"],
            "exact2d",
        ),
        (
            vec!["kernel", "--preset", "skin1", "--method", "magic"],
            "magic",
        ),
        (
            vec![
                "kernel", "--preset", "skin1", "--k", "5", "--method", "guided",
            ],
            "--k",
        ),
        (
            vec![
                "kernel",
                "--preset",
                "skin1",
                "--artist-preset",
                "production",
            ],
            "--method artist",
        ),
        (
            vec![
                "kernel",
                "--preset",
                "skin1",
                "--method",
                "artist",
                "--artist-preset",
                "x",
            ],
            "x",
        ),
        (
            vec!["kernel", "--sigma-a", "-1,1,1", "--sigma-s", "1,1,1"],
            "sigma_a",
        ),
        (
            vec!["kernel", "--preset", "skin1", "--format", "yaml"],
            "yaml",
        ),
    ];
    for (args, needle) in cases {
        let o = sss(&args);
        assert!(!o.status.success(), "{args:?} succeeded");
        let err = stderr(&o);
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: `{needle}` not in {err}");
        assert!(stdout(&o).is_empty(), "{args:?}");
    }
}

/// The names a message or a help text lists after `marker` (up to `end`), split at ", " and
/// " or ".
fn listed<'a>(text: &'a str, marker: &str, end: char) -> Vec<&'a str> {
    let rest = text
        .split_once(marker)
        .unwrap_or_else(|| panic!("`{marker}` not in {text}"))
        .1;
    let list = &rest[..rest
        .find(end)
        .unwrap_or_else(|| panic!("no `{end}` in {rest}"))];
    list.split(", ")
        .flat_map(|s| s.split(" or "))
        .map(str::trim)
        .collect()
}

/// Lists of names in errors and help come from their one source: a model, kernel, artist
/// preset, built-in scene or `--selection` value added there cannot be missing from them.
#[test]
fn errors_and_help_list_every_name_of_their_registry() {
    let models: Vec<&str> = ModelKind::ALL.iter().map(|k| k.name()).collect();
    for command in [
        vec!["kernel", "--preset", "skin1", "--model", "nope"],
        vec![
            "filter",
            "in.exr",
            "--preset",
            "skin1",
            "--units-per-mm",
            "1",
            "--out",
            "out.exr",
            "--model",
            "nope",
        ],
    ] {
        let o = sss(&command);
        assert_eq!(o.status.code(), Some(2), "{command:?}");
        let err = stderr(&o);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert_eq!(listed(&err, "(expected ", ')'), models, "{err}");
    }
    let help = ok(&["kernel", "--help"]);
    let flat = help.split_whitespace().collect::<Vec<_>>().join(" ");
    assert_eq!(
        listed(&flat, "approximated (one of: ", ')'),
        models,
        "{flat}"
    );

    use sss_render::kernel_choice::KernelMethod;
    let separable: Vec<&str> = KernelMethod::ALL
        .iter()
        .filter(|k| **k != KernelMethod::Exact2d)
        .map(|k| k.name())
        .collect();
    let err = stderr(&sss(&[
        "kernel", "--preset", "skin1", "--method", "exact2d",
    ]));
    assert_eq!(listed(&err, "choose one of ", '\n'), separable, "{err}");
    assert_eq!(
        listed(&flat, "The kernel (one of: ", ';'),
        separable,
        "{flat}"
    );

    let artist: Vec<&str> = sss_separable::artist::PRESETS
        .iter()
        .map(|p| p.name)
        .collect();
    assert_eq!(listed(&flat, "parameter set (one of: ", ')'), artist);
    let err = stderr(&sss(&[
        "kernel",
        "--preset",
        "skin1",
        "--method",
        "artist",
        "--artist-preset",
        "x",
    ]));
    assert_eq!(listed(&err, "(known: ", ')'), artist, "{err}");

    let help = ok(&["render", "--help"]);
    let flat = help.split_whitespace().collect::<Vec<_>>().join(" ");
    let scenes: Vec<&str> = sss_render::scene::BUILTIN_SCENES
        .iter()
        .map(|(n, _)| *n)
        .collect();
    assert_eq!(listed(&flat, "built-in scene (", ')'), scenes, "{flat}");
    assert_eq!(
        listed(&flat, "screen-space convolution (one of: ", ')'),
        KernelMethod::NAMES,
        "{flat}"
    );
    assert_eq!(
        listed(&flat, "(Max-Extent) (one of: ", ')'),
        sss_render::integrators::manylight::SELECTIONS,
        "{flat}"
    );
}

/// The separable integrator on a scene: close to the exact world-space reference on a sphere
/// (screen-space blur of the same irradiance), energy kept, silhouettes respected.
#[test]
fn separable_render_is_close_to_exact() {
    let dir = tmp_dir("separable");
    let scene = tiny_scene(&dir);
    let scene = scene.to_str().unwrap();
    let ex = dir.join("ex.exr");
    let sep = dir.join("sep.exr");
    ok(&["render", scene, "--out", ex.to_str().unwrap()]);
    ok(&[
        "render",
        scene,
        "--method",
        "separable",
        "--out",
        sep.to_str().unwrap(),
    ]);
    let d = ok(&["diff", sep.to_str().unwrap(), ex.to_str().unwrap()]);
    let ratio: Vec<f64> = d
        .lines()
        .find_map(|l| l.strip_prefix("mean_ratio "))
        .unwrap()
        .split_whitespace()
        .map(|v| v.parse().unwrap())
        .collect();
    for r in ratio {
        assert!((r - 1.0).abs() < 0.1, "{d}");
    }
}

/// `sss render --method separable --gbuffer` writes the screen-space inputs and `sss filter`
/// reproduces the render's pass from them: render = F_t(η, cos θ_o)/(cπ) × filter output, with
/// F_t ≤ 1 and ≈ F_t(η, 1) at the pixel facing the camera.
#[test]
fn filter_reads_the_gbuffer_and_reproduces_the_pass() {
    use sss_bssrdf::fresnel::ft_dielectric;
    use sss_bssrdf::fresnel_normalization;
    let dir = tmp_dir("filter");
    let scene = tiny_scene(&dir);
    let (gb, sep, fil) = (dir.join("g.exr"), dir.join("s.exr"), dir.join("f.exr"));
    ok(&[
        "render",
        scene.to_str().unwrap(),
        "--method",
        "separable",
        "--gbuffer",
        gb.to_str().unwrap(),
        "--out",
        sep.to_str().unwrap(),
    ]);
    let text = ok(&[
        "filter",
        gb.to_str().unwrap(),
        "--preset",
        "skin1",
        "--units-per-mm",
        "0.1",
        "--out",
        fil.to_str().unwrap(),
    ]);
    assert!(text.contains("translucent pixels"), "{text}");
    let (_, _, s) = sss_render::image::read_exr(&sep).unwrap();
    let (_, _, f) = sss_render::image::read_exr(&fil).unwrap();
    let sub = &s.iter().find(|(n, _)| n == "subsurface").unwrap().1;
    let ex = &f.iter().find(|(n, _)| n == "exitance").unwrap().1;
    let norm = 1.0 / (fresnel_normalization(1.3) * std::f64::consts::PI);
    let mut max_ratio: f64 = 0.0;
    let mut lit = 0;
    for i in 0..sub.len() {
        for c in 0..3 {
            if ex[i][c] <= 1e-12 {
                assert!(
                    sub[i][c] <= 1e-9,
                    "pixel {i}: render {} without exitance",
                    sub[i][c]
                );
                continue;
            }
            let r = sub[i][c] / (ex[i][c] * norm);
            assert!(r <= 1.0 + 1e-4, "pixel {i} channel {c}: ratio {r}");
            max_ratio = max_ratio.max(r);
            lit += 1;
        }
    }
    assert!(lit > 30, "{lit}");
    let ft1 = ft_dielectric(1.0, 1.3);
    assert!(
        (max_ratio - ft1).abs() < 0.01,
        "max ratio {max_ratio} vs F_t(1) {ft1}"
    );
    // Bad input: a file without the layers, and --gbuffer without the separable method.
    // (The separable render's `--out` holds them too, as its own layers.)
    let plain = dir.join("plain.exr");
    sss_render::image::write_exr(&plain, 2, 2, &[("total", &[[0.5; 3]; 4])]).unwrap();
    let o = sss(&[
        "filter",
        plain.to_str().unwrap(),
        "--preset",
        "skin1",
        "--units-per-mm",
        "0.1",
        "--out",
        fil.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("irradiance"), "{}", stderr(&o));
    let o = sss(&[
        "render",
        scene.to_str().unwrap(),
        "--gbuffer",
        gb.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--method separable"), "{}", stderr(&o));
    let o = sss(&[
        "filter",
        gb.to_str().unwrap(),
        "--preset",
        "skin1",
        "--units-per-mm",
        "0",
        "--out",
        fil.to_str().unwrap(),
    ]);
    assert!(stderr(&o).contains("--units-per-mm"), "{}", stderr(&o));
}

/// A binding cap and a flag of another method are reported on stderr as `warning:` lines;
/// the render still succeeds.
#[test]
fn render_warns_when_a_cap_binds_and_for_foreign_flags() {
    let dir = tmp_dir("render-warnings");
    let scene = dir.join("ball.toml");
    std::fs::write(
        &scene,
        "[camera]\nposition = [0.0, 0.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\n\
         fov = 30.0\nresolution = [16, 12]\n\n[[lights]]\ntype = \"directional\"\n\
         direction = [0.0, 0.0, -1.0]\nirradiance = 1.0\n\n[materials.wax]\n\
         type = \"translucent\"\nmodel = \"better-dipole\"\npreset = \"skin1\"\n\
         units_per_mm = 0.1\n\n[[objects]]\nname = \"ball\"\nmaterial = \"wax\"\n\
         shape = \"sphere\"\nradius = 1.0\n",
    )
    .unwrap();
    let path = scene.to_str().unwrap();
    let o = sss(&["render", path, "--max-samples", "300", "--spp", "4"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    let lines: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("warning: ") && !l.contains("not kept"))
        .collect();
    assert_eq!(lines.len(), 2, "{err}");
    assert!(
        lines[0].contains("--spp") && lines[0].contains("exact"),
        "{err}"
    );
    assert!(
        lines[1].contains("cap of 300") && lines[1].contains("--max-samples"),
        "{err}"
    );
    assert!(
        stdout(&o).contains("irradiance samples: "),
        "{}",
        stdout(&o)
    );
    // Without an output file: the one warning says the image is not kept.
    let o = sss(&["render", path]);
    assert!(o.status.success());
    let err = stderr(&o);
    let lines: Vec<&str> = err.lines().filter(|l| l.starts_with("warning: ")).collect();
    assert_eq!(lines.len(), 1, "{err}");
    assert!(
        lines[0].contains("--out") && lines[0].contains("not kept"),
        "{err}"
    );

    // Over the memory budget: one error line, exit 2, no output file.
    let out = dir.join("x.exr");
    let o = sss(&[
        "render",
        path,
        "--max-memory",
        "1K",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.starts_with("error: ") && err.contains("--max-memory"),
        "{err}"
    );
    assert!(!out.exists());
    let names: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 1, "only the scene file: {names:?}");
}

#[test]
fn profile_over_the_memory_budget_is_one_error_line_and_no_plot() {
    let dir = std::env::temp_dir().join(format!("sss-profile-budget-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let plot = dir.join("p.png");
    // 10^15 steps would abort if allocated; the default budget refuses them first.
    for (model, steps, budget) in [
        ("pbd", "1000000000000000", None),
        ("monte-carlo", "1000000000000000", None),
        // Within the hard limits, but 10^5 rows need more than 1 MiB.
        ("burley", "100000", Some("1M")),
        ("monte-carlo", "100000", Some("1M")),
    ] {
        let mut args = vec![
            "profile", "--model", model, "--preset", "skin1", "--r-max", "4", "--steps", steps,
            "--plot",
        ];
        args.push(plot.to_str().unwrap());
        if let Some(b) = budget {
            args.extend(["--max-memory", b]);
        }
        let o = sss(&args);
        assert_eq!(o.status.code(), Some(2), "{model} {steps}");
        let err = stderr(&o);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.starts_with("error: "), "{err}");
        assert!(err.contains(&format!("--steps {steps}")), "{err}");
        assert!(
            err.contains("needs about ") && err.contains("memory budget of "),
            "{err}"
        );
        if budget.is_some() {
            assert!(err.contains("budget of 1048576 bytes"), "{err}");
        }
        assert!(stdout(&o).is_empty());
        assert!(!plot.exists());
    }
    // The same request under a sufficient budget succeeds.
    let o = sss(&[
        "profile",
        "--model",
        "burley",
        "--preset",
        "skin1",
        "--r-max",
        "4",
        "--steps",
        "100000",
        "--max-memory",
        "1G",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn filter_and_diff_refuse_an_exr_whose_header_exceeds_the_budget() {
    let dir = std::env::temp_dir().join(format!("sss-exr-budget-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("huge.exr");
    let px = vec![[1.0f64; 3]; 4];
    sss_render::image::write_exr(&path, 2, 2, &[("irradiance", &px), ("surface", &px)]).unwrap();
    let small = dir.join("small.exr");
    std::fs::copy(&path, &small).unwrap();
    // Patch every dataWindow (name, type `box2i`, size 16, then xMin yMin xMax yMax as i32
    // LE; OpenEXR file layout) to 0..=99999: 10¹⁰ pixels of at least 12 bytes each.
    let mut bytes = std::fs::read(&path).unwrap();
    let key = b"dataWindow\0box2i\0";
    let hits: Vec<usize> = (0..bytes.len() - key.len())
        .filter(|&i| &bytes[i..i + key.len()] == key)
        .collect();
    assert!(!hits.is_empty());
    for at in hits {
        let v = at + key.len() + 4;
        for (i, x) in [0i32, 0, 99_999, 99_999].iter().enumerate() {
            bytes[v + 4 * i..v + 4 * i + 4].copy_from_slice(&x.to_le_bytes());
        }
    }
    std::fs::write(&path, &bytes).unwrap();
    let out = dir.join("out.exr");
    let (p, s, o) = (
        path.to_str().unwrap(),
        small.to_str().unwrap(),
        out.to_str().unwrap(),
    );
    for args in [
        vec![
            "filter",
            p,
            "--preset",
            "skin1",
            "--units-per-mm",
            "1",
            "--out",
            o,
            "--max-memory",
            "1G",
        ],
        vec!["diff", p, s, "--max-memory", "1G"],
        vec!["diff", s, p, "--max-memory", "1G"],
    ] {
        let r = sss(&args);
        assert_eq!(r.status.code(), Some(2), "{args:?}");
        let err = stderr(&r);
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(err.starts_with("error: "), "{err}");
        assert!(
            err.contains("huge.exr") && err.contains("100000x100000"),
            "{err}"
        );
        assert!(err.contains("memory budget of 1073741824 bytes"), "{err}");
        assert!(!out.exists());
    }
    // Two small files under a budget that holds both (2 × 2 layers × 4 px × 36 bytes = 576).
    assert!(
        sss(&["diff", s, s, "--layer", "surface", "--max-memory", "576"])
            .status
            .success()
    );
    let r = sss(&["diff", s, s, "--layer", "surface", "--max-memory", "575"]);
    assert_eq!(r.status.code(), Some(2), "{}", stderr(&r));
    std::fs::remove_dir_all(&dir).ok();
}

/// `--exposure SCALE` scales the PNG's linear values before the sRGB curve (IEC 61966-2-1),
/// checked pixel by pixel against the EXR written beside it; a bad scale is refused by name.
#[test]
fn render_png_takes_one_exposure() {
    let dir = tmp_dir("exposure");
    let scene = tiny_scene(&dir);
    let (exr, png_path) = (dir.join("e.exr"), dir.join("e.png"));
    let srgb = |v: f64| {
        let v = v.clamp(0.0, 1.0);
        let s = if v <= 0.0031308 {
            12.92 * v
        } else {
            1.055 * v.powf(1.0 / 2.4) - 0.055
        };
        s * 255.0
    };
    for exposure in ["0.5", "3"] {
        ok(&[
            "render",
            scene.to_str().unwrap(),
            "--method",
            "separable",
            "--out",
            exr.to_str().unwrap(),
            "--png",
            png_path.to_str().unwrap(),
            "--exposure",
            exposure,
        ]);
        let (_, _, layers) = sss_render::image::read_exr(&exr).unwrap();
        let total = &layers.iter().find(|(n, _)| n == "total").unwrap().1;
        let decoder = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(&png_path).unwrap(),
        ));
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        let step = info.color_type.samples();
        let e: f64 = exposure.parse().unwrap();
        let mut lit = 0;
        for (p, px) in total.iter().zip(buf.chunks_exact(step)) {
            for c in 0..3 {
                let want = srgb(p[c] * e);
                assert!(
                    (f64::from(px[c]) - want).abs() <= 0.51,
                    "exposure {e}: {} against {want}",
                    px[c]
                );
                lit += usize::from(want > 10.0 && want < 245.0);
            }
        }
        assert!(
            lit > 30,
            "exposure {e}: too few pixels between black and white"
        );
    }
    let o = sss(&[
        "render",
        scene.to_str().unwrap(),
        "--png",
        png_path.to_str().unwrap(),
        "--exposure",
        "0",
    ]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("not an exposure"), "{}", stderr(&o));
}
