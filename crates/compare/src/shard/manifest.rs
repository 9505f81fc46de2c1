//! What a shard records of itself (`shard.txt`: settings, version, plan, host) and of its
//! report sections, and the checks a merge makes of a set of shards before joining them.

use super::*;

/// The version of the code: the package version and the git commit of the workspace (with
/// `+dirty` when tracked files differ from it), or `unknown` without git.
pub(super) fn version() -> String {
    let root = crate::workspace_root();
    let root = root.as_path();
    let git = |args: &[&str]| {
        std::process::Command::new("git")
            .arg("-C")
            .arg(root)
            .args(args)
            .output()
            .ok()
            .filter(|o| o.status.success())
            .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
    };
    let commit = git(&["rev-parse", "HEAD"]).unwrap_or_else(|| "unknown".into());
    let dirty =
        git(&["status", "--porcelain", "--untracked-files=no"]).is_some_and(|s| !s.is_empty());
    format!(
        "{} {commit}{}",
        env!("CARGO_PKG_VERSION"),
        if dirty { "+dirty" } else { "" }
    )
}

/// The settings that decide a run's results, as `key=value` lines in a fixed order: shards
/// of one run agree on all of them.
pub(super) fn settings(config: &Config, outline: &PlanOutline) -> Vec<(&'static str, String)> {
    vec![
        ("format", FORMAT.to_string()),
        ("version", version()),
        ("quick", config.quick.to_string()),
        (
            "exposure",
            config.exposure.map_or("auto".into(), |e| format!("{e:e}")),
        ),
        ("seed", config.seed.to_string()),
        ("photons", config.photons.to_string()),
        ("bins", config.bins.to_string()),
        ("presets", escape(&config.presets.join(","))),
        ("scenes", escape(&config.scenes.join(","))),
        ("loaded", escape(&outline.scenes.join(","))),
        (
            "skipped",
            outline
                .skipped
                .iter()
                .map(|s| escape(s))
                .collect::<Vec<_>>()
                .join("\t"),
        ),
        ("units", outline.units.len().to_string()),
    ]
}

/// A report section as a file: the title, then the summary and the body after marker lines.
pub(super) fn section_text(s: &Section) -> String {
    format!(
        "{}\n<!-- sss-shard summary -->\n{}<!-- sss-shard body -->\n{}",
        s.title, s.summary, s.body
    )
}

pub(super) fn parse_section(text: &str, path: &Path) -> Result<Section, Error> {
    let bad = || {
        Error(format!(
            "{}: not a section written by a shard",
            path.display()
        ))
    };
    let (title, rest) = text
        .split_once("\n<!-- sss-shard summary -->\n")
        .ok_or_else(bad)?;
    let (summary, body) = rest
        .split_once("<!-- sss-shard body -->\n")
        .ok_or_else(bad)?;
    Ok(Section {
        title: title.to_string(),
        summary: summary.to_string(),
        body: body.to_string(),
    })
}

/// A shard's manifest, read back.
pub(super) struct Manifest {
    pub(super) dir: PathBuf,
    pub(super) shard: Shard,
    /// The settings, in [`settings`]'s order.
    pub(super) settings: Vec<(String, String)>,
    pub(super) seconds: f64,
}

impl Manifest {
    /// The value of setting `k` (empty when absent).
    pub(super) fn setting(&self, k: &str) -> String {
        self.settings
            .iter()
            .find(|(key, _)| key == k)
            .map(|(_, v)| v.clone())
            .unwrap_or_default()
    }
}

pub(super) fn read_manifest(dir: &Path) -> Result<Manifest, Error> {
    let path = dir.join(MANIFEST);
    let text = std::fs::read_to_string(&path).map_err(|e| {
        Error(format!(
            "{}: cannot read ({e}); is it the directory of a finished `--shard` run?",
            path.display()
        ))
    })?;
    let mut map: Vec<(String, String)> = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let (k, v) = line
            .split_once('=')
            .ok_or_else(|| Error(format!("{}:{}: not key=value", path.display(), n + 1)))?;
        map.push((k.to_string(), v.to_string()));
    }
    let get = |k: &str| {
        map.iter()
            .find(|(key, _)| key == k)
            .map(|(_, v)| v.clone())
            .ok_or_else(|| Error(format!("{}: no `{k}`", path.display())))
    };
    let format = get("format")?;
    if format != FORMAT.to_string() {
        return Err(Error(format!(
            "{}: shard format {format}, this version reads {FORMAT}",
            path.display()
        )));
    }
    let shard: Shard = get("shard")?
        .parse()
        .map_err(|e| Error(format!("{}: {e}", path.display())))?;
    let seconds = get("seconds")?.parse().unwrap_or(f64::NAN);
    let keys = [
        "format", "version", "quick", "exposure", "seed", "photons", "bins", "presets", "scenes",
        "loaded", "skipped", "units",
    ];
    let settings = keys
        .iter()
        .map(|k| Ok((k.to_string(), get(k)?)))
        .collect::<Result<_, Error>>()?;
    Ok(Manifest {
        dir: dir.to_path_buf(),
        shard,
        settings,
        seconds,
    })
}

/// Checks that `manifests` are the shards 1..N of one run; the error names the difference.
pub(super) fn check_shards(manifests: &[Manifest]) -> Result<(), Error> {
    let first = &manifests[0];
    for m in &manifests[1..] {
        for ((k, a), (_, b)) in first.settings.iter().zip(&m.settings) {
            if a != b {
                return Err(Error(format!(
                    "cannot merge: shard {} ({}) has {k}={b} but shard {} ({}) has {k}={a}",
                    m.shard,
                    m.dir.display(),
                    first.shard,
                    first.dir.display()
                )));
            }
        }
        if m.shard.count != first.shard.count {
            return Err(Error(format!(
                "cannot merge: {} is shard {} but {} is shard {}",
                m.dir.display(),
                m.shard,
                first.dir.display(),
                first.shard
            )));
        }
    }
    let n = first.shard.count;
    for i in 1..=n {
        let with: Vec<&Manifest> = manifests.iter().filter(|m| m.shard.index == i).collect();
        match with.len() {
            1 => {}
            0 => {
                return Err(Error(format!(
                    "cannot merge: shard {i}/{n} is missing (got {})",
                    manifests
                        .iter()
                        .map(|m| format!("{} from {}", m.shard, m.dir.display()))
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            }
            _ => {
                return Err(Error(format!(
                    "cannot merge: shard {i}/{n} is given twice ({})",
                    with.iter()
                        .map(|m| m.dir.display().to_string())
                        .collect::<Vec<_>>()
                        .join(" and ")
                )));
            }
        }
    }
    Ok(())
}

/// The settings of the run the shards made, as a config writing into `out`.
pub(super) fn merged_config(m: &Manifest, out: &Path) -> Result<Config, Error> {
    let get = |k: &str| m.setting(k);
    let bad = |k: &str| Error(format!("{}: bad `{k}`", m.dir.join(MANIFEST).display()));
    let list = |k: &str| -> Result<Vec<String>, Error> {
        let text = unescape(&get(k)).ok_or_else(|| bad(k))?;
        Ok(text
            .split(',')
            .filter(|s| !s.is_empty())
            .map(String::from)
            .collect())
    };
    Ok(Config {
        photons: get("photons").parse().map_err(|_| bad("photons"))?,
        seed: get("seed").parse().map_err(|_| bad("seed"))?,
        bins: get("bins").parse().map_err(|_| bad("bins"))?,
        quick: get("quick").parse().map_err(|_| bad("quick"))?,
        exposure: match get("exposure").as_str() {
            "auto" => None,
            e => Some(e.parse().map_err(|_| bad("exposure"))?),
        },
        ..Config::new(list("presets")?, list("scenes")?, out.to_path_buf())
    })
}
