//! Joining the shards' directories into the outputs of an unsharded run: their pictures
//! copied, their runs read back, the report and `results.csv` written anew.

use super::*;

/// Copies every file under `from` into `to` (same relative paths), but the shard's records
/// and its cache.
pub(super) fn copy_outputs(from: &Path, to: &Path, top: bool) -> Result<(), Error> {
    let entries = std::fs::read_dir(from)
        .map_err(|e| Error(format!("cannot read {}: {e}", from.display())))?;
    for entry in entries {
        let entry = entry.map_err(|e| Error(format!("cannot read {}: {e}", from.display())))?;
        let name = entry.file_name();
        let name_str = name.to_string_lossy();
        let path = entry.path();
        if top && (RECORDS.contains(&name_str.as_ref()) || NOT_COPIED.contains(&name_str.as_ref()))
        {
            continue;
        }
        let target = to.join(&name);
        if path.is_dir() {
            std::fs::create_dir_all(&target)
                .map_err(|e| Error(format!("cannot create {}: {e}", target.display())))?;
            copy_outputs(&path, &target, false)?;
        } else if path.is_file() {
            let bytes = std::fs::read(&path)
                .map_err(|e| Error(format!("cannot read {}: {e}", path.display())))?;
            write_atomic(&target, &bytes)?;
        }
    }
    Ok(())
}

/// Reads a shard's `runs.tsv` into `results` (by unit index); a unit given twice is an error.
pub(super) fn read_runs(dir: &Path, results: &mut [Option<UnitResult>]) -> Result<(), Error> {
    let path = dir.join(RUNS);
    let text = std::fs::read_to_string(&path)
        .map_err(|e| Error(format!("{}: cannot read ({e})", path.display())))?;
    let bad = |n: usize, why: String| Error(format!("{}:{}: {why}", path.display(), n + 1));
    let mut lines = text.lines().enumerate();
    while let Some((n, line)) = lines.next() {
        let f: Vec<&str> = line.splitn(4, '\t').collect();
        if f.len() != 4 || f[0] != "unit" {
            return Err(bad(n, "expected `unit` INDEX runs|unsupported ...".into()));
        }
        let ui: usize = f[1].parse().map_err(|_| bad(n, "bad unit index".into()))?;
        let result = match f[2] {
            "runs" => {
                let k: usize = f[3].parse().map_err(|_| bad(n, "bad run count".into()))?;
                let mut runs = Vec::with_capacity(k);
                for _ in 0..k {
                    let (n, line) = lines
                        .next()
                        .ok_or_else(|| bad(n, format!("{k} runs announced, file ends")))?;
                    runs.push(scenes::Run::from_record(line).map_err(|e| bad(n, e))?);
                }
                UnitResult::Runs(runs)
            }
            "unsupported" => {
                UnitResult::Unsupported(unescape(f[3]).ok_or_else(|| bad(n, "bad escape".into()))?)
            }
            other => return Err(bad(n, format!("unknown result `{other}`"))),
        };
        let slot = results
            .get_mut(ui)
            .ok_or_else(|| bad(n, format!("unit {ui} is not in the plan")))?;
        if slot.is_some() {
            return Err(bad(
                n,
                format!("unit {ui} was already given by another shard"),
            ));
        }
        *slot = Some(result);
    }
    Ok(())
}

/// `--merge DIR...`: joins shard directories into `config.out`.
pub fn merge(dirs: &[PathBuf], out: &Path) -> Result<(), Error> {
    let manifests = dirs
        .iter()
        .map(|d| read_manifest(d))
        .collect::<Result<Vec<_>, _>>()?;
    if manifests.is_empty() {
        return Err(Error("--merge needs at least one shard directory".into()));
    }
    check_shards(&manifests)?;
    let out_real = out.canonicalize().ok();
    let same = |a: &Path| out_real.is_some() && a.canonicalize().ok() == out_real;
    if let Some(m) = manifests.iter().find(|m| same(&m.dir)) {
        return Err(Error(format!(
            "cannot merge into {}: it is shard {}'s own directory; give --out another one",
            out.display(),
            m.shard
        )));
    }
    let config = merged_config(&manifests[0], out)?;
    let presets = crate::check(&config)?;
    std::fs::create_dir_all(out)
        .map_err(|e| Error(format!("cannot create {}: {e}", out.display())))?;
    let setting = |k: &str| manifests[0].setting(k);
    let scene_names: Vec<String> = unescape(&setting("loaded"))
        .unwrap_or_default()
        .split(',')
        .filter(|s| !s.is_empty())
        .map(String::from)
        .collect();
    let skipped: Vec<String> = setting("skipped")
        .split('\t')
        .filter(|s| !s.is_empty())
        .map(|s| unescape(s).unwrap_or_default())
        .collect();
    let units = SweepUnit::all(scene_names.len(), config.quick);
    if units.len().to_string() != setting("units") {
        return Err(Error(format!(
            "cannot merge: the shards planned {} units, this version plans {}",
            setting("units"),
            units.len()
        )));
    }
    let mut results: Vec<Option<UnitResult>> = vec![None; units.len()];
    let mut info: Vec<Option<SceneInfo>> = vec![None; scene_names.len()];
    let mut sections: BTreeMap<&str, Section> = BTreeMap::new();
    for m in &manifests {
        read_runs(&m.dir, &mut results)?;
        let path = m.dir.join(SCENES);
        let text = std::fs::read_to_string(&path)
            .map_err(|e| Error(format!("{}: cannot read ({e})", path.display())))?;
        for (n, line) in text.lines().enumerate() {
            let bad = |why: String| Error(format!("{}:{}: {why}", path.display(), n + 1));
            let (head, rest) = line
                .strip_prefix("scene\t")
                .and_then(|l| l.split_once('\t'))
                .ok_or_else(|| bad("expected `scene` INDEX ...".into()))?;
            let si: usize = head.parse().map_err(|_| bad("bad scene index".into()))?;
            let parsed = SceneInfo::from_record(rest).map_err(bad)?;
            let slot = info
                .get_mut(si)
                .ok_or_else(|| bad(format!("scene {si} is not in the plan")))?;
            slot.get_or_insert(parsed);
        }
        for name in ["profiles", "kernels"] {
            let path = m.dir.join(format!("section_{name}.md"));
            if path.exists() {
                let text = std::fs::read_to_string(&path)
                    .map_err(|e| Error(format!("{}: cannot read ({e})", path.display())))?;
                if sections
                    .insert(name, parse_section(&text, &path)?)
                    .is_some()
                {
                    return Err(Error(format!(
                        "cannot merge: two shards ran the {name} comparison"
                    )));
                }
            }
        }
        copy_outputs(&m.dir, out, true)?;
    }
    let missing: Vec<usize> = (0..units.len()).filter(|&i| results[i].is_none()).collect();
    if let Some(&first) = missing.first() {
        return Err(Error(format!(
            "cannot merge: {} sweep unit(s) missing from every shard (first: unit {first})",
            missing.len()
        )));
    }
    let results: Vec<UnitResult> = results.into_iter().flatten().collect();
    let outline = PlanOutline {
        scenes: scene_names,
        skipped,
        units,
    };
    let log = |msg: &str| eprintln!("{msg}");
    let ctx = Context {
        config: &config,
        references: &[],
        log: &log,
    };
    let scenes_section = scenes::assemble(&ctx, &outline, &info, &results)?;
    let mut all = Vec::new();
    for (name, section) in [
        ("profiles", sections.remove("profiles")),
        ("scenes", Some(scenes_section)),
        ("kernels", sections.remove("kernels")),
    ] {
        all.push(section.ok_or_else(|| {
            Error(format!(
                "cannot merge: no shard holds the {name} comparison"
            ))
        })?);
    }
    let seconds: Vec<f64> = manifests.iter().map(|m| m.seconds).collect();
    let report = crate::assemble_report(
        &config,
        &presets,
        &all,
        seconds.iter().sum(),
        Some(&format!(
            "Merged from {} shards (`--shard I/{}`), {} s in all; per shard: {} s.",
            manifests.len(),
            manifests.len(),
            crate::output::md_num(Some(seconds.iter().sum()), 3),
            seconds
                .iter()
                .map(|s| crate::output::md_num(Some(*s), 3))
                .collect::<Vec<_>>()
                .join(", ")
        )),
    );
    let path = out.join("report.md");
    write_atomic(&path, report.as_bytes())?;
    crate::html::write(out, &report)?;
    eprintln!("merge: {} shards -> {}", manifests.len(), path.display());
    Ok(())
}
