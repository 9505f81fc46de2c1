//! Rules of the workspace's layout that a compiler does not check.

use std::path::{Path, PathBuf};

/// The workspace root (this crate lives in `tests/`).
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ has a parent")
        .to_path_buf()
}

/// Every file under `dir` that `keep` accepts, recursively.
fn files_where(dir: &Path, keep: &dyn Fn(&Path) -> bool, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            files_where(&p, keep, out);
        } else if keep(&p) {
            out.push(p);
        }
    }
}

/// Every file under `dir` whose extension is `ext`, recursively.
fn files_with_extension(dir: &Path, ext: &str, out: &mut Vec<PathBuf>) {
    files_where(dir, &|p| p.extension().is_some_and(|x| x == ext), out);
}

/// Every `.rs` file under `dir`, recursively.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    files_with_extension(dir, "rs", out);
}

/// Whether `text` uses the `unsafe` keyword outside comments (a block, fn, impl or trait).
fn uses_unsafe(text: &str) -> bool {
    text.lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .any(|l| {
            l.split(|c: char| !(c.is_alphanumeric() || c == '_'))
                .any(|w| w == "unsafe")
        })
}

/// Crates whose sources hold no `unsafe` forbid it in every target root (`src/lib.rs`,
/// `src/main.rs`), so that none creeps in unreviewed. The Python bindings are the one
/// exception: PyO3's macros expand to `unsafe` code inside the crate, which the lint would
/// refuse.
#[test]
fn crates_without_unsafe_code_forbid_it() {
    let root = root();
    let mut dirs: Vec<PathBuf> = std::fs::read_dir(root.join("crates"))
        .expect("crates/ exists")
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.join("Cargo.toml").is_file())
        .collect();
    dirs.push(root.join("xtask"));
    dirs.sort();
    let mut missing = Vec::new();
    let mut checked = 0;
    for dir in &dirs {
        if dir.file_name().is_some_and(|n| n == "python") {
            continue;
        }
        let mut files = Vec::new();
        rust_files(&dir.join("src"), &mut files);
        let has_unsafe = files
            .iter()
            .any(|f| uses_unsafe(&std::fs::read_to_string(f).unwrap_or_default()));
        if has_unsafe {
            continue;
        }
        for target in ["src/lib.rs", "src/main.rs"] {
            let f = dir.join(target);
            let Ok(text) = std::fs::read_to_string(&f) else {
                continue;
            };
            checked += 1;
            if !text.contains("#![forbid(unsafe_code)]") {
                missing.push(f.strip_prefix(&root).unwrap_or(&f).display().to_string());
            }
        }
    }
    assert!(
        checked >= 10,
        "only {checked} target roots found under {}",
        root.display()
    );
    assert!(
        missing.is_empty(),
        "without `#![forbid(unsafe_code)]`: {}",
        missing.join(", ")
    );
}

#[test]
fn the_unsafe_scan_reads_code_not_comments_or_names() {
    assert!(uses_unsafe("    unsafe { x }"));
    assert!(uses_unsafe("pub unsafe fn f() {}"));
    assert!(!uses_unsafe("// an unsafe remark"));
    assert!(!uses_unsafe("#![forbid(unsafe_code)]"));
    assert!(!uses_unsafe("let not_unsafe = 1;"));
}

/// Every member of the workspace inherits its lints (`[lints] workspace = true`), so a lint
/// allowed or denied for the workspace is allowed or denied once, in the root `Cargo.toml`.
#[test]
fn every_member_inherits_the_workspace_lints() {
    let root = root();
    let manifest = std::fs::read_to_string(root.join("Cargo.toml")).expect("root Cargo.toml");
    assert!(
        manifest.contains("[workspace.lints"),
        "no [workspace.lints] table"
    );
    let members = manifest
        .split("members = [")
        .nth(1)
        .and_then(|s| s.split(']').next())
        .expect("a members list");
    let mut missing = Vec::new();
    let mut n = 0;
    for m in members.split(',').map(|s| s.trim().trim_matches('"')) {
        if m.is_empty() {
            continue;
        }
        n += 1;
        let text = std::fs::read_to_string(root.join(m).join("Cargo.toml")).unwrap_or_default();
        let inherits = text
            .split("[lints]")
            .nth(1)
            .is_some_and(|rest| rest.trim_start().starts_with("workspace = true"));
        if !inherits {
            missing.push(m.to_string());
        }
    }
    assert!(n >= 10, "only {n} members read");
    assert!(
        missing.is_empty(),
        "not inheriting the workspace lints: {missing:?}"
    );
}

/// The module names of the paths in `code` that start at `super::` or `integrators::` (comments
/// stripped): every identifier of each such path, braces included, so `super::{a, b::c}` gives
/// `a`, `b`, `c`.
fn integrator_path_names(code: &str) -> Vec<String> {
    let code: String = code
        .lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n");
    let mut names = Vec::new();
    for start in ["super::", "integrators::"] {
        let mut from = 0;
        while let Some(i) = code[from..].find(start) {
            let begin = from + i + start.len();
            // The path runs over identifiers, `::` and balanced braces.
            let mut depth = 0usize;
            let mut end = begin;
            for (k, c) in code[begin..].char_indices() {
                let ok = c.is_alphanumeric()
                    || c == '_'
                    || c == ':'
                    || c == '{'
                    || (depth > 0 && (c == '}' || c == ',' || c.is_whitespace()));
                if !ok {
                    break;
                }
                match c {
                    '{' => depth += 1,
                    '}' => depth -= 1,
                    _ => {}
                }
                end = begin + k + c.len_utf8();
            }
            names.extend(
                code[begin..end]
                    .split(|c: char| !(c.is_alphanumeric() || c == '_'))
                    .filter(|w| !w.is_empty())
                    .map(str::to_string),
            );
            from = begin;
        }
    }
    names
}

/// The render crate's integrators keep their shared code above them (the family's `mod.rs`,
/// `integrators/mod.rs`, `options.rs`, a shared module such as the VPL family's `vpls`, or a
/// crate module): a method file that imported from a sibling method would make one method's
/// change silently another's, as option specs shared by array position once did. A method file
/// is one named for a registered method (`dual-tree-fmm` in `dual_tree_fmm.rs`).
#[test]
fn no_method_file_imports_from_a_sibling_method() {
    let dir = root().join("crates/render/src/integrators");
    let mut files = Vec::new();
    rust_files(&dir, &mut files);
    let stem = |p: &Path| p.file_stem().unwrap().to_string_lossy().into_owned();
    let registered: Vec<String> = sss_render::integrators::METHODS
        .iter()
        .map(|m| m.name.replace('-', "_"))
        .collect();
    let methods: Vec<PathBuf> = files
        .into_iter()
        .filter(|p| registered.contains(&stem(p)))
        .collect();
    let names: Vec<String> = methods.iter().map(|p| stem(p)).collect();
    let mut found = names.clone();
    found.sort();
    let mut want = registered.clone();
    want.sort();
    assert_eq!(
        found,
        want,
        "one file per registered method under {}",
        dir.display()
    );
    let mut offences = Vec::new();
    for p in &methods {
        let own = stem(p);
        let text = std::fs::read_to_string(p).unwrap();
        for n in integrator_path_names(&text) {
            if n != own && names.contains(&n) {
                offences.push(format!("{} names `{n}`", p.display()));
            }
        }
    }
    offences.sort();
    offences.dedup();
    assert!(
        offences.is_empty(),
        "method files import from sibling methods (move the shared code into the family's \
         mod.rs or options.rs):\n{}",
        offences.join("\n")
    );
}

#[test]
fn the_path_scan_sees_groups_and_chains_but_not_comments() {
    let names = integrator_path_names(
        "use super::{Counts, exact::Exact};\nuse crate::integrators::vpl::manylight;\n\
         // super::dual_tree in a comment\nlet x = super::super::mdlc::f();",
    );
    for want in ["Counts", "exact", "Exact", "vpl", "manylight", "mdlc"] {
        assert!(
            names.iter().any(|n| n == want),
            "{want} missing from {names:?}"
        );
    }
    assert!(!names.iter().any(|n| n == "dual_tree"), "{names:?}");
}

/// The top-level entries a repository path in the docs starts with.
const TOP: [&str; 9] = [
    "crates/", "docs/", "scenes/", "tests/", "xtask/", "fuzz/", ".ci/", ".cargo/", "results/",
];

/// The repository paths `text` names: text in backticks or a Markdown link's target that
/// starts with a top-level entry ([`TOP`]), with `{a,b}` groups expanded (an element `…` is
/// left out), trailing punctuation and `:line` suffixes cut, and placeholders (`<…>`, `*`,
/// `…`, a segment such as `TARGET`), generated output (`target/`) and fenced code blocks
/// (commands and sample output) left out.
fn named_paths(text: &str) -> Vec<String> {
    let mut fenced = false;
    let prose: Vec<&str> = text
        .lines()
        .filter(|l| {
            if l.trim_start().starts_with("```") {
                fenced = !fenced;
                return false;
            }
            !fenced
        })
        .collect();
    let text = prose.join("\n");
    let text = text.as_str();
    let mut candidates: Vec<&str> = Vec::new();
    for (i, part) in text.split('`').enumerate() {
        if i % 2 == 1 {
            candidates.push(part);
        }
    }
    let mut rest = text;
    while let Some(k) = rest.find("](") {
        rest = &rest[k + 2..];
        if let Some(end) = rest.find(')') {
            candidates.push(&rest[..end]);
        }
    }
    let mut out = Vec::new();
    for c in candidates {
        let c = c.trim().split(['#', ' ']).next().unwrap_or("");
        let c = c.trim_end_matches([',', '.', ';', ':']);
        let placeholder = c
            .split(['/', '.'])
            .any(|seg| ["TARGET", "DIR", "NAME", "FILE", "CRATE"].contains(&seg));
        if !TOP.iter().any(|t| c.starts_with(t)) || c.contains(['<', '*', '$']) || placeholder {
            continue;
        }
        // `path:line` or `path:line:col`.
        let c = match c.split_once(':') {
            Some((p, tail)) if tail.chars().all(|x| x.is_ascii_digit() || x == ':') => p,
            _ => c,
        };
        for p in expand_braces(c) {
            if !p.contains('…') && !p.contains("...") {
                out.push(p);
            }
        }
    }
    out
}

/// `a/{b,c}.rs` as `a/b.rs` and `a/c.rs` (one group; none: the path itself).
fn expand_braces(p: &str) -> Vec<String> {
    match (p.find('{'), p.find('}')) {
        (Some(a), Some(b)) if a < b => p[a + 1..b]
            .split(',')
            .flat_map(|x| expand_braces(&format!("{}{}{}", &p[..a], x.trim(), &p[b + 1..])))
            .collect(),
        _ => vec![p.to_string()],
    }
}

/// The README, ARCHITECTURE.md, every page under `docs/` and `scenes/`, and every crate's
/// documentation (the `//!` lines of its `src/lib.rs`) name only repository paths that exist:
/// a file moved without its docs fails here, naming the document and the path.
#[test]
fn docs_name_only_paths_that_exist() {
    let root = root();
    let mut docs = vec![root.join("README.md"), root.join("ARCHITECTURE.md")];
    files_with_extension(&root.join("docs"), "md", &mut docs);
    files_with_extension(&root.join("scenes"), "md", &mut docs);
    let mut crate_docs = Vec::new();
    for dir in ["crates", "tests", "xtask"] {
        rust_files(&root.join(dir), &mut crate_docs);
    }
    crate_docs.retain(|p| p.ends_with("src/lib.rs"));
    let mut missing = Vec::new();
    for doc in docs.iter().chain(&crate_docs) {
        let text = std::fs::read_to_string(doc).unwrap();
        let text: String = if doc.extension().is_some_and(|x| x == "rs") {
            text.lines()
                .filter_map(|l| l.trim_start().strip_prefix("//!"))
                .collect::<Vec<_>>()
                .join("\n")
        } else {
            text
        };
        for p in named_paths(&text) {
            if !root.join(&p).exists() {
                missing.push(format!(
                    "{}: `{p}`",
                    doc.strip_prefix(&root).unwrap_or(doc).display()
                ));
            }
        }
    }
    assert!(
        missing.is_empty(),
        "{} paths named in the docs do not exist:\n{}",
        missing.len(),
        missing.join("\n")
    );
}

/// The path scan by hand: backticks and links, groups, line suffixes, placeholders.
#[test]
fn the_doc_path_scan_reads_backticks_links_and_groups() {
    let text = "See `crates/a/src/{b,c}.rs`, [d](docs/e.md#part) and `crates/f.rs:12:3`; \
                not `target/x`, `crates/<crate>/g.rs`, `crates/{h,…}.rs`, `fuzz/TARGET.dict` \
                or `src/i.rs`.\n```\nsss render scenes/nothing.toml\n```\n";
    assert_eq!(
        named_paths(text),
        [
            "crates/a/src/b.rs",
            "crates/a/src/c.rs",
            "crates/f.rs",
            "crates/h.rs",
            "docs/e.md"
        ]
    );
}

/// The workspace crates a manifest depends on (its `[dependencies]` and `[dev-dependencies]`
/// keys named `sss-…`, less the build-only `sss-workspace-hack`), without the prefix.
fn workspace_dependencies(manifest: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut in_deps = false;
    for line in manifest.lines() {
        let l = line.trim();
        if l.starts_with('[') {
            in_deps = l == "[dependencies]" || l == "[dev-dependencies]";
            continue;
        }
        if !in_deps {
            continue;
        }
        let key = l.split(['=', '.', ' ']).next().unwrap_or("");
        if let Some(name) = key.strip_prefix("sss-")
            && name != "workspace-hack"
            && !out.iter().any(|o| o == name)
        {
            out.push(name.to_string());
        }
    }
    out
}

/// ARCHITECTURE.md's crate table says, in its last column, which workspace crates each crate
/// depends on: for every row, the workspace crates named there are exactly those its
/// `Cargo.toml` names (dependencies and dev-dependencies), so the table cannot drift from the
/// manifests.
#[test]
fn the_architecture_table_names_each_crates_dependencies() {
    let root = root();
    let text = std::fs::read_to_string(root.join("ARCHITECTURE.md")).unwrap();
    let crates: Vec<String> = std::fs::read_dir(root.join("crates"))
        .unwrap()
        .flatten()
        .filter(|e| e.path().join("Cargo.toml").exists())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    let mut rows = 0;
    let mut wrong = Vec::new();
    for line in text.lines().filter(|l| l.starts_with("| `")) {
        let cells: Vec<&str> = line.split(" | ").collect();
        let folder = cells[0].trim_start_matches("| ").trim_matches('`');
        let manifest = root.join(folder).join("Cargo.toml");
        let Ok(manifest) = std::fs::read_to_string(&manifest) else {
            continue;
        };
        rows += 1;
        let last = cells
            .last()
            .unwrap()
            .trim_end_matches(" |")
            .trim_end_matches('|');
        let named: Vec<String> = last
            .split([',', ';'])
            .map(|w| w.split_whitespace().next().unwrap_or("").to_string())
            .filter(|w| crates.contains(w) && w != "workspace-hack")
            .collect();
        let mut actual = workspace_dependencies(&manifest);
        actual.sort();
        let mut named_sorted = named.clone();
        named_sorted.sort();
        named_sorted.dedup();
        if actual != named_sorted {
            wrong.push(format!(
                "{folder}: the table names {named_sorted:?}, Cargo.toml {actual:?}"
            ));
        }
    }
    assert!(rows >= 15, "only {rows} rows of the crate table read");
    assert!(
        wrong.is_empty(),
        "ARCHITECTURE.md's dependencies:\n{}",
        wrong.join("\n")
    );
}

/// Only the binary depends on the libraries: no crate depends on `sss-cli` but `xtask` (its
/// clap definitions make the generated reference and the argument fuzzer) and this test crate
/// (as a dev-dependency, to test the CLI's own code); what a command does lives in the library
/// that owns the idea.
#[test]
fn nothing_but_xtask_and_tests_depends_on_the_binary_crate() {
    let root = root();
    let mut manifests: Vec<PathBuf> = std::fs::read_dir(root.join("crates"))
        .unwrap()
        .flatten()
        .map(|e| e.path().join("Cargo.toml"))
        .filter(|p| p.exists())
        .collect();
    manifests.push(root.join("xtask/Cargo.toml"));
    manifests.push(root.join("tests/Cargo.toml"));
    assert!(manifests.len() >= 15, "{manifests:?}");
    let mut users = Vec::new();
    for path in &manifests {
        let text = std::fs::read_to_string(path).unwrap();
        if workspace_dependencies(&text).iter().any(|d| d == "cli") {
            let folder = path.parent().unwrap().strip_prefix(&root).unwrap();
            users.push(folder.display().to_string());
        }
    }
    users.sort();
    assert_eq!(users, ["tests", "xtask"], "crates that depend on sss-cli");
    // The test crate only as a dev-dependency: its library half does not.
    let tests = std::fs::read_to_string(root.join("tests/Cargo.toml")).unwrap();
    let deps = tests.split("[dev-dependencies]").next().unwrap();
    assert!(
        !workspace_dependencies(deps).iter().any(|d| d == "cli"),
        "tests/Cargo.toml: sss-cli outside [dev-dependencies]"
    );
}

/// The manifest scan by hand: both dependency tables, dotted and inline keys, the build-only
/// hack and other sections left out, each crate once.
#[test]
fn the_manifest_scan_reads_both_dependency_tables() {
    let manifest = "[package]\nname = \"sss-x\"\n\n[dependencies]\nsss-util.workspace = true\n\
                    sss-gpu = { workspace = true, optional = true }\nglam.workspace = true\n\
                    sss-workspace-hack.workspace = true\n\n[dev-dependencies]\n\
                    sss-peers.workspace = true\nsss-util.workspace = true\n\n\
                    [features]\nsss-render = []\n";
    assert_eq!(workspace_dependencies(manifest), ["util", "gpu", "peers"]);
}

/// The first date in `line` of the form `YYYY-MM-DD` (four ASCII digits, a dash, two, a dash,
/// two; the numbers are not checked as a calendar's), if any, less the dates that name a record
/// in `results/` (`results/YYYY-MM-DD-topic.md`), which the docs cite for their figures.
fn first_date(line: &str) -> Option<&str> {
    const SHAPE: &[u8; 10] = b"dddd-dd-dd";
    let b = line.as_bytes();
    (0..b.len().saturating_sub(SHAPE.len() - 1))
        .find(|&i| {
            let shaped = SHAPE.iter().zip(&b[i..]).all(|(&s, &c)| {
                if s == b'd' {
                    c.is_ascii_digit()
                } else {
                    c == s
                }
            });
            shaped && !b[..i].ends_with(b"results/")
        })
        // The match is ASCII, so both ends are character boundaries.
        .map(|i| &line[i..i + SHAPE.len()])
}

/// The docs carry no dated lab notes: README.md, ARCHITECTURE.md, every file under `docs/` and
/// every crate's `src/lib.rs` say what is measured, how, and what it means, without a date of
/// the form `YYYY-MM-DD`. The figures of a dated run (date, host, command, commit) live in
/// `results/`, which is exempt: one file per record, `results/YYYY-MM-DD-topic.md`, which the
/// docs may name.
#[test]
fn docs_carry_no_dates() {
    let root = root();
    let mut files = vec![root.join("README.md"), root.join("ARCHITECTURE.md")];
    files_where(&root.join("docs"), &|_| true, &mut files);
    let mut crate_roots = Vec::new();
    for dir in ["crates", "tests", "xtask"] {
        rust_files(&root.join(dir), &mut crate_roots);
    }
    crate_roots.retain(|p| p.ends_with("src/lib.rs"));
    assert!(
        crate_roots.len() >= 10,
        "only {} crate roots found under {}",
        crate_roots.len(),
        root.display()
    );
    files.extend(crate_roots);
    let mut dated = Vec::new();
    for f in &files {
        let bytes = std::fs::read(f).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        let text = String::from_utf8_lossy(&bytes);
        for (n, line) in text.lines().enumerate() {
            if let Some(date) = first_date(line) {
                dated.push(format!(
                    "{}:{}: {date}",
                    f.strip_prefix(&root).unwrap_or(f).display(),
                    n + 1
                ));
            }
        }
    }
    assert!(
        dated.is_empty(),
        "{} dated lines in the docs (move the dated figures to a `results/YYYY-MM-DD-topic.md` \
         and link it):\n{}",
        dated.len(),
        dated.join("\n")
    );
}

/// The date scan by hand: a date anywhere in a line, alone or in a range; not a record's name in
/// `results/`, nor anything else of digits and dashes or dots.
#[test]
fn the_date_scan_finds_dates_and_only_dates() {
    assert_eq!(first_date("2026-12-05"), Some("2026-12-05"));
    assert_eq!(
        first_date("Measured on 2026-12-05 (21 minutes)"),
        Some("2026-12-05")
    );
    assert_eq!(
        first_date("the earlier run of 2026-12-04/05, then 2027-01-02"),
        Some("2026-12-04")
    );
    assert_eq!(first_date("–×·2026-12-05·"), Some("2026-12-05"));
    assert_eq!(
        first_date("figures: `results/2026-12-05-trees.md`, run on 2026-12-06"),
        Some("2026-12-06")
    );
    for not_a_date in [
        "",
        "1-2-3",
        "version 0.30",
        "in 2026",
        "2026-12",
        "2026-1-05",
        "26-12-05",
        "2026/12/05",
        "2026-12-0",
        "12 026-12-05",
        "commit `9d7f230`, 1 309 CPU-seconds, 0.3–0.75 mm",
        "the figures of the last run: `results/2026-12-05-compare-trees.md`",
        "[a record](results/2026-12-05-compare-trees.md)",
    ] {
        assert_eq!(first_date(not_a_date), None, "{not_a_date:?}");
    }
}
