//! The shard merge of `sss-compare` (`sss_compare::run` with `Config::merge`, which is
//! `cargo xtask compare --merge DIR`) on one shard directory made from the input: the input is
//! split at NUL bytes into the files a shard's directory holds, in the order `shard.txt`
//! (the manifest), `runs.tsv`, `scenes.tsv`, `section_profiles.md`, `section_kernels.md`;
//! files past the input's last part are absent, and so is a report section whose part is empty
//! (a shard writes only the sections of its items). The merge writes into a second directory.
//! It reads the manifest (`read_manifest`), checks the set of shards, reads the runs
//! (`read_runs`), the scene facts and the report sections (`parse_section`), and, when all of
//! them are valid, assembles the report.
#![no_main]

mod common;

use libfuzzer_sys::fuzz_target;
use sss_compare::{Config, run};

/// The files of a shard's directory, in the order the input's parts fill them.
const FILES: [&str; 5] = [
    "shard.txt",
    "runs.tsv",
    "scenes.tsv",
    "section_profiles.md",
    "section_kernels.md",
];

fuzz_target!(|data: &[u8]| {
    let work = common::work_dir("shard_manifest");
    let (shard, out) = (work.join("shard"), work.join("merged"));
    let _ = std::fs::remove_dir_all(&shard);
    let _ = std::fs::remove_dir_all(&out);
    std::fs::create_dir_all(&shard).expect("fuzz driver: cannot create the shard directory");
    for (i, (name, part)) in FILES.iter().zip(data.split(|&b| b == 0)).enumerate() {
        if i < 3 || !part.is_empty() {
            common::write(&shard.join(name), part);
        }
    }
    let config = Config {
        merge: vec![shard],
        ..Config::new(Vec::new(), Vec::new(), out)
    };
    let _ = run(&config);
});
