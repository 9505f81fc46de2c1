use super::super::Config;
use super::*;
use sss_render::Stage;

fn config(out: PathBuf) -> Config {
    Config {
        photons: 1,
        bins: 1,
        quick: true,
        ..Config::new(vec!["skin1".into()], vec!["s".into()], out)
    }
}

fn results(units: &[SweepUnit], hosts: &[Host]) -> Vec<UnitResult> {
    units
        .iter()
        .enumerate()
        .map(|(i, u)| {
            let m = &METHODS[u.method];
            let host = hosts[i % hosts.len()].clone();
            let run = Run {
                scene: "s".into(),
                method: m.name,
                param: m.sweep.label,
                value: (m.sweep.values)(true)[u.value],
                threads: host.cores,
                host,
                stages: vec![Stage {
                    name: "shading",
                    seconds: 1.0 + i as f64,
                }],
                rmse: 0.1,
                rel_rmse: 0.1,
                frac_within_eps: 0.5,
                within_3se: None,
                mean_ratio: 1.0,
                flip: 0.0,
                warnings: Vec::new(),
            };
            if m.name == "eelc" {
                UnitResult::Unsupported("needs a radial model".into())
            } else {
                UnitResult::Runs(vec![run])
            }
        })
        .collect()
}

/// Rows timed on different hosts are flagged in the report (a host column and the list of
/// hosts) and named in `results.csv`; rows of one host are not flagged. Units after a
/// method's unsupported one are left out, and the method is listed as unsupported.
#[test]
fn mixed_hosts_are_flagged() {
    let dir = std::env::temp_dir().join(format!("xtask-hosts-{}", std::process::id()));
    let cfg = config(dir.clone());
    std::fs::create_dir_all(&dir).unwrap();
    let log = |_: &str| {};
    let ctx = Context {
        config: &cfg,
        references: &[],
        log: &log,
    };
    let units = SweepUnit::all(1, true);
    let outline = PlanOutline {
        scenes: vec!["s".into()],
        skipped: vec!["`bunny`: no mesh".into()],
        units: units.clone(),
    };
    let info = vec![Some(SceneInfo {
        width: 8,
        height: 6,
        pixels: 40,
        samples: 100,
        seconds: 1.5,
        threads: 2,
    })];
    let a = Host {
        cpu: "cpu A".into(),
        cores: 2,
    };
    let b = Host {
        cpu: "cpu B".into(),
        cores: 64,
    };
    let one = assemble(
        &ctx,
        &outline,
        &info,
        &results(&units, std::slice::from_ref(&a)),
    )
    .unwrap();
    assert!(!one.summary.contains("different hosts"), "{}", one.summary);
    assert!(one.summary.contains("`eelc` on `s`: needs a radial model"));
    assert!(one.summary.contains("Skipped `bunny`: no mesh"));
    let mixed = assemble(&ctx, &outline, &info, &results(&units, &[a, b])).unwrap();
    assert!(
        mixed.summary.contains("from 2 different hosts")
            && mixed.summary.contains("H1: cpu A (2 cores)")
            && mixed.summary.contains("H2: cpu B (64 cores)"),
        "{}",
        mixed.summary
    );
    assert!(mixed.body.contains("| host |"), "{}", mixed.body);
    let csv = std::fs::read_to_string(dir.join("results.csv")).unwrap();
    assert!(csv.lines().next().unwrap().contains(",host,host_cores,"));
    assert!(
        csv.contains(",cpu A,2,") && csv.contains(",cpu B,64,"),
        "{csv}"
    );
    assert!(!csv.contains("eelc"), "{csv}");
    let rows = csv.lines().count() - 1;
    let eelc = units
        .iter()
        .filter(|u| METHODS[u.method].name == "eelc")
        .count();
    assert_eq!(rows, units.len() - eelc);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Every column of the experiment's CSV is documented in `docs/compare.md`.
#[test]
fn every_csv_column_is_documented() {
    assert_eq!(
        crate::output::undocumented(&results_csv(&[])),
        Vec::<String>::new()
    );
}

/// The sweep scores methods against `exact` with their own model: every model-bound method
/// has units, `volpath` (bound to no model) none.
#[test]
fn the_sweep_runs_every_model_bound_method_and_not_volpath() {
    let units = SweepUnit::all(2, true);
    for (mi, m) in METHODS.iter().enumerate() {
        let n = units.iter().filter(|u| u.method == mi).count();
        if m.name == "volpath" {
            assert_eq!(n, 0);
        } else {
            assert_eq!(n, 2 * (m.sweep.values)(true).len(), "{}", m.name);
        }
    }
}
