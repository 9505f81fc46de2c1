use super::*;

#[test]
fn shard_parses_and_refuses() {
    assert_eq!("2/3".parse::<Shard>(), Ok(Shard { index: 2, count: 3 }));
    assert_eq!("1/1".parse::<Shard>(), Ok(Shard { index: 1, count: 1 }));
    for (text, why) in [
        ("0/0", "N must be at least 1"),
        ("3/2", "I must lie in 1..=N"),
        ("0/2", "I must lie in 1..=N"),
        ("a/2", "I is not a number"),
        ("1/b", "N is not a number"),
        ("12", "no `/`"),
        ("-1/2", "I is not a number"),
    ] {
        let e = text.parse::<Shard>().unwrap_err();
        assert!(e.contains(why) && e.contains(text), "{text}: {e}");
        assert!(!e.contains('\n'));
    }
}

/// Every item goes to exactly one shard, the largest first to the emptiest, so no shard
/// carries more than the ideal share plus the largest item (the LPT bound).
#[test]
fn assignment_is_balanced_and_complete() {
    let costs: Vec<f64> = (0..40).map(|i| ((i * 37) % 11 + 1) as f64).collect();
    for n in 1..6 {
        let a = assign(&costs, n);
        assert_eq!(a.len(), costs.len());
        assert!(a.iter().all(|&s| s < n));
        let mut load = vec![0.0; n];
        for (i, &s) in a.iter().enumerate() {
            load[s] += costs[i];
        }
        let total: f64 = costs.iter().sum();
        let max = costs.iter().cloned().fold(0.0, f64::max);
        for l in &load {
            assert!(*l <= total / n as f64 + max, "{load:?}");
        }
        assert_eq!(a, assign(&costs, n), "deterministic");
    }
    // Ties go to the lower shard, in item order.
    assert_eq!(assign(&[1.0, 1.0, 1.0, 1.0], 2), [0, 1, 0, 1]);
    assert_eq!(assign(&[1.0, 5.0, 1.0], 2), [1, 0, 1]);
}

#[test]
fn sections_round_trip() {
    let s = Section {
        title: "Profiles".into(),
        summary: "a | b\n|---|\n".into(),
        body: "## x\n\ntext\n".into(),
    };
    let back = parse_section(&section_text(&s), Path::new("x")).unwrap();
    assert_eq!(
        (back.title, back.summary, back.body),
        (s.title, s.summary, s.body)
    );
    assert!(parse_section("just text", Path::new("x")).is_err());
}

/// Relative paths of the files under `dir`, but the cache, the report, results.csv and a
/// shard's records.
fn outputs(dir: &Path, prefix: &Path, into: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let e = e.unwrap();
        let name = e.file_name().to_string_lossy().to_string();
        let rel = prefix.join(&name);
        if prefix.as_os_str().is_empty()
            && (NOT_COPIED.contains(&name.as_str()) || RECORDS.contains(&name.as_str()))
        {
            continue;
        }
        if e.path().is_dir() {
            outputs(&e.path(), &rel, into);
        } else {
            into.push(rel);
        }
    }
    into.sort();
}

/// Three shards (reading references a `--prepare` job computed) and their merge give the
/// rows, error figures, pictures and report sections of one unsharded run; merges of
/// incomplete, repeated or mismatched shards are refused with the difference named.
#[test]
fn shards_merge_to_the_unsharded_run() {
    let root = std::env::temp_dir().join(format!("xtask-shards-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    // The built-in sphere, small: what is tested is the bookkeeping of shards and merges,
    // which every method's rows, pictures and report sections go through at any size (the
    // built-in scene took most of this crate's test time in CI).
    let scene = root.join("small.toml");
    let text = sss_render::scene::BUILTIN_SCENES
        .iter()
        .find(|(n, _)| *n == "sphere")
        .expect("the built-in sphere")
        .1
        .replace("resolution = [160, 120]", "resolution = [48, 36]")
        .replace("units_per_mm = 0.05", "units_per_mm = 0.15");
    assert!(text.contains("[48, 36]") && text.contains("0.15"), "{text}");
    std::fs::write(&scene, text).unwrap();
    let base = Config {
        photons: 2000,
        bins: 20,
        quick: true,
        ..Config::new(
            vec!["skin1".into()],
            vec![scene.to_string_lossy().into_owned()],
            root.join("whole"),
        )
    };
    super::super::run(&base).unwrap();
    let shared = Config {
        cache: Some(root.join("shared-cache")),
        out: root.join("prepare"),
        ..base.clone()
    };
    super::super::run(&Config {
        prepare: true,
        ..shared.clone()
    })
    .unwrap();
    let dirs: Vec<PathBuf> = (1..=3).map(|i| root.join(format!("s{i}"))).collect();
    for (i, dir) in dirs.iter().enumerate() {
        super::super::run(&Config {
            shard: Some(Shard {
                index: i + 1,
                count: 3,
            }),
            out: dir.clone(),
            ..shared.clone()
        })
        .unwrap();
    }
    let merged = root.join("merged");
    super::super::run(&Config {
        merge: dirs.clone(),
        out: merged.clone(),
        ..base.clone()
    })
    .unwrap();

    // results.csv: the same rows; every column but the times equal.
    let whole = std::fs::read_to_string(base.out.join("results.csv")).unwrap();
    let joined = std::fs::read_to_string(merged.join("results.csv")).unwrap();
    let (wl, jl): (Vec<&str>, Vec<&str>) = (whole.lines().collect(), joined.lines().collect());
    assert_eq!(wl.len(), jl.len());
    assert!(wl.len() > 10, "{whole}");
    assert_eq!(wl[0], jl[0], "the same columns");
    let header: Vec<&str> = wl[0].split(',').collect();
    for (a, b) in wl[1..].iter().zip(&jl[1..]) {
        let (a, b): (Vec<&str>, Vec<&str>) = (a.split(',').collect(), b.split(',').collect());
        for (k, col) in header.iter().enumerate() {
            if !col.starts_with("seconds_") {
                assert_eq!(a[k], b[k], "column {col}");
            }
        }
    }
    // The same pictures and tables.
    let (mut a, mut b) = (Vec::new(), Vec::new());
    outputs(&base.out, Path::new(""), &mut a);
    outputs(&merged, Path::new(""), &mut b);
    assert_eq!(a, b);
    assert!(
        a.iter().any(|p| p.ends_with("pathtrace_16_error.png")),
        "{a:?}"
    );
    for csv in ["profiles.csv", "kernels.csv"] {
        let cols = |text: &str| -> Vec<String> {
            // The error columns: those not named for seconds, times or ns.
            let mut lines = text.lines();
            let h: Vec<&str> = lines.next().unwrap().split(',').collect();
            lines
                .flat_map(|l| {
                    l.split(',')
                        .zip(&h)
                        .filter(|(_, c)| {
                            !(c.contains("seconds") || c.contains("ns_") || c.contains("_ns"))
                        })
                        .map(|(v, _)| v.to_string())
                        .collect::<Vec<_>>()
                })
                .collect()
        };
        let x = std::fs::read_to_string(base.out.join(csv)).unwrap();
        let y = std::fs::read_to_string(merged.join(csv)).unwrap();
        assert_eq!(cols(&x), cols(&y), "{csv}");
    }
    let report = std::fs::read_to_string(merged.join("report.md")).unwrap();
    let headings = |t: &str| -> Vec<String> {
        t.lines()
            .filter(|l| l.starts_with('#'))
            .map(String::from)
            .collect()
    };
    let whole_report = std::fs::read_to_string(base.out.join("report.md")).unwrap();
    assert_eq!(headings(&report), headings(&whole_report));
    assert!(report.contains("Merged from 3 shards"), "{report}");
    // report.html: the same viewers, pictures and chart points either way (timings differ).
    let html = |d: &Path| std::fs::read_to_string(d.join("report.html")).unwrap();
    let (hw, hm) = (html(&base.out), html(&merged));
    for pat in ["<section class=\"viewer\"", "<img", "<circle", "<table>"] {
        assert_eq!(hw.matches(pat).count(), hm.matches(pat).count(), "{pat}");
    }
    assert!(hm.matches("<section class=\"viewer\"").count() >= 1);
    assert!(hm.contains("Merged from 3 shards"));

    // Refusals.
    let merge = |dirs: Vec<PathBuf>| {
        super::super::run(&Config {
            merge: dirs,
            out: root.join("refused"),
            ..base.clone()
        })
        .unwrap_err()
        .to_string()
    };
    let e = merge(dirs[..2].to_vec());
    assert!(e.contains("shard 3/3 is missing"), "{e}");
    let e = merge(vec![dirs[0].clone(), dirs[1].clone(), dirs[1].clone()]);
    assert!(e.contains("shard 2/3 is given twice"), "{e}");
    let e = super::super::run(&Config {
        merge: dirs.clone(),
        out: dirs[2].clone(),
        ..base.clone()
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("shard 3/3's own directory"), "{e}");
    let e = merge(vec![root.join("prepare")]);
    assert!(e.contains("shard.txt") && e.contains("cannot read"), "{e}");
    let manifest = dirs[1].join(MANIFEST);
    let text = std::fs::read_to_string(&manifest).unwrap();
    for (from, to, named) in [
        ("seed=1\n", "seed=2\n", "seed=2"),
        ("version=", "version=0.0.0 other", "version=0.0.0 other"),
        ("quick=true", "quick=false", "quick=false"),
    ] {
        assert!(text.contains(from), "{from}");
        std::fs::write(&manifest, text.replacen(from, to, 1)).unwrap();
        let e = merge(dirs.clone());
        assert!(e.contains(named) && e.contains("cannot merge"), "{e}");
        assert!(!e.contains('\n'), "{e}");
    }
    std::fs::write(&manifest, &text).unwrap();
    std::fs::remove_dir_all(&root).unwrap();
}
