//! `cargo xtask fuzz`: fuzzing on stable Rust with a seeded mutator.
//!
//! Four targets ([`targets::Target`]): `scene` (scene TOML through `sss_scene::load_str` and
//! `load`), `obj` (a scene naming a mutated OBJ mesh), `exr` (`read_exr` and `sss filter` on
//! mutated EXR bytes) and `cli` (`sss` argument lists parsed and run in-process, behind a
//! guard that keeps each run small: see [`targets::guard`]). Each target starts from a corpus
//! ([`corpus`]) and runs, at iteration `i`, a mutant ([`mutate`]) drawn from a generator
//! seeded by (seed, target, i) alone: the first iterations run the corpus unchanged, and the
//! inputs of a seed are always the same (a time limit only decides how many are run).
//!
//! Each input runs on a worker thread under `catch_unwind` with a time limit. A panic is
//! reported (seed, target, iteration, message) with the input saved to
//! `target/fuzz/crashes/<target>-<hash>.bin` and the run goes on; a hang is reported the same
//! way and ends the run at once (the stuck thread cannot be stopped). An abort (stack
//! overflow, out of memory) kills the worker process: the driver runs the fuzzing in a child
//! process, which writes each input to `target/fuzz/inflight.bin` before running it, and the
//! parent reports that input when the child dies. Any crash makes the exit status 1.
//! `--replay FILE` runs one saved input.

pub mod corpus;
pub mod exr_values;
pub mod mutate;
pub mod targets;

use mutate::Rng;
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::mpsc;
use std::time::{Duration, Instant};
use targets::{Harness, Ran, Target};

/// Iterations per target when neither `--iterations` nor `--seconds` is given.
pub const DEFAULT_ITERATIONS: u64 = 1000;

/// Stack of the worker thread running one input (the size of a main thread's, so recursion
/// limits behave as in `sss`).
const WORKER_STACK: usize = 8 << 20;

/// What `cargo xtask fuzz` was asked to do.
#[derive(Clone, Debug)]
pub struct Config {
    /// Seed of every mutation.
    pub seed: u64,
    /// Most iterations per target.
    pub iterations: Option<u64>,
    /// Wall-clock budget over all targets, split evenly between them.
    pub seconds: Option<f64>,
    /// The targets, in order.
    pub targets: Vec<Target>,
    /// Time limit of one input; longer is a hang.
    pub per_input: Duration,
    /// Where work files, crashes and the in-flight input go (`target/fuzz`).
    pub out: PathBuf,
    /// Searched for OBJ files for the `obj` corpus (skipped when absent).
    pub shared_meshes: PathBuf,
    /// Run one saved input (with the single target given) instead of fuzzing.
    pub replay: Option<PathBuf>,
}

/// A crash found.
#[derive(Debug)]
struct Crash {
    kind: &'static str,
    message: String,
    file: PathBuf,
}

/// The tallies of one target, for its summary line.
#[derive(Default)]
struct Tally {
    iterations: u64,
    inputs: u64,
    ok: u64,
    skipped: std::collections::BTreeMap<&'static str, u64>,
    errors: HashSet<String>,
    crashes: u64,
}

/// The last panic's message and location, recorded by the hook [`run_worker`] installs.
static LAST_PANIC: Mutex<Option<String>> = Mutex::new(None);

fn install_panic_hook() {
    std::panic::set_hook(Box::new(|info| {
        let message = sss_cli::panic_message(info);
        let mut last = LAST_PANIC.lock().unwrap_or_else(|e| e.into_inner());
        // Keep the first panic of an input (a worker's, not the re-raise on its caller).
        if last.is_none() {
            *last = Some(message);
        }
    }));
}

/// FNV-1a of the input: the crash file's name.
fn hash(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// Saves a crashing input and prints the report line.
fn report(
    config: &Config,
    target: Target,
    iteration: u64,
    kind: &'static str,
    message: &str,
    input: &[u8],
) -> Crash {
    let dir = config.out.join("crashes");
    let file = dir.join(format!("{}-{:016x}.bin", target.name(), hash(input)));
    let saved = std::fs::create_dir_all(&dir).and_then(|()| std::fs::write(&file, input));
    let note = match saved {
        Ok(()) => String::new(),
        Err(e) => format!(" (could not save the input: {e})"),
    };
    println!(
        "CRASH {kind}: target {} seed {} iteration {iteration}: {message}; input {}{note}\n  \
         replay: cargo xtask fuzz --target {} --replay {}",
        target.name(),
        config.seed,
        file.display(),
        target.name(),
        file.display()
    );
    Crash {
        kind,
        message: message.to_string(),
        file,
    }
}

/// The outcome of one guarded run.
enum Verdict {
    Ran(Ran),
    Panicked(String),
    Hung,
}

/// Runs `input` on `target` on a worker thread under `catch_unwind`, waiting at most `limit`.
fn guarded(target: Target, dir: &Path, input: &[u8], limit: Duration) -> Verdict {
    *LAST_PANIC.lock().unwrap_or_else(|e| e.into_inner()) = None;
    let (tx, rx) = mpsc::channel();
    let (dir, input) = (dir.to_path_buf(), input.to_vec());
    let spawned = std::thread::Builder::new()
        .name("fuzz-input".into())
        .stack_size(WORKER_STACK)
        .spawn(move || {
            let r = std::panic::catch_unwind(|| targets::run(target, &dir, &input));
            let _ = tx.send(r.ok());
        });
    let handle = match spawned {
        Ok(h) => h,
        Err(e) => return Verdict::Panicked(format!("fuzz driver: cannot start a worker: {e}")),
    };
    match rx.recv_timeout(limit) {
        Ok(Some(ran)) => {
            let _ = handle.join();
            Verdict::Ran(ran)
        }
        Ok(None) => {
            let _ = handle.join();
            let msg = LAST_PANIC
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .take()
                .unwrap_or_else(|| "panic".into());
            Verdict::Panicked(msg)
        }
        Err(mpsc::RecvTimeoutError::Disconnected) => {
            let _ = handle.join();
            Verdict::Panicked("the worker ended without a result".into())
        }
        Err(mpsc::RecvTimeoutError::Timeout) => Verdict::Hung,
    }
}

/// The in-flight files: the input about to run and where it comes from.
fn inflight(out: &Path) -> (PathBuf, PathBuf) {
    (out.join("inflight.bin"), out.join("inflight.txt"))
}

/// The input of `iteration`: the corpus entries first, then mutants.
fn input_at(config: &Config, h: &Harness, iteration: u64) -> Vec<u8> {
    let n = h.corpus.len() as u64;
    if iteration < n {
        return h.corpus[iteration as usize].clone();
    }
    let mut rng = Rng::new(config.seed, &[h.target.id(), iteration]);
    let base = rng.pick(&h.corpus).clone();
    let other = rng.pick(&h.corpus).clone();
    if h.target == Target::Exr && rng.one_in(2) {
        // Written by the `exr` crate outside the guard: a failure (or a panic of the
        // writer) falls back to a byte-level mutant.
        let path = h.dir.join("mutant.exr");
        let mut gen_rng = rng.clone();
        let made = std::panic::catch_unwind(move || exr_values::mutant(&path, &mut gen_rng));
        if let Ok(Ok(bytes)) = made {
            return bytes;
        }
    }
    if h.target == Target::Cli {
        let args = targets::split_args(&base);
        if args.get(1).is_some_and(|a| a == "render") && rng.one_in(3) {
            // A render of a mutated tiny scene (arguments unchanged).
            let scene = corpus::tiny_sphere_scene().into_bytes();
            let other = rng.pick(&corpus::scenes()).clone();
            let text = mutate::mutate(&scene, &other, true, &mut rng, targets::MAX_FILE_LEN);
            return targets::join_args_scene(&args, &text);
        }
        let pool: Vec<&str> = h.pool.iter().map(String::as_str).collect();
        let m = mutate::mutate_args(&args, &pool, &mut rng, targets::MAX_ARG_LEN);
        targets::join_args(&m)
    } else {
        mutate::mutate(&base, &other, h.text, &mut rng, targets::MAX_FILE_LEN)
    }
}

/// Fuzzes one target until its iterations or its deadline run out. Returns the crashes and
/// whether the run must stop (a hang).
fn fuzz_target(
    config: &Config,
    target: Target,
    deadline: Option<Instant>,
) -> Result<(Vec<Crash>, bool), String> {
    let dir = config.out.join("work").join(target.name());
    let h = Harness::new(target, &dir, &config.shared_meshes)?;
    let (flight_bin, flight_txt) = inflight(&config.out);
    let max_iter = match (config.iterations, config.seconds) {
        (Some(n), _) => n,
        (None, Some(_)) => u64::MAX,
        (None, None) => DEFAULT_ITERATIONS,
    };
    let replay = match &config.replay {
        Some(p) => Some(std::fs::read(p).map_err(|e| format!("{}: {e}", p.display()))?),
        None => None,
    };
    let mut tally = Tally::default();
    let mut crashes = Vec::new();
    let mut stop = false;
    let t0 = Instant::now();
    let mut i = 0u64;
    while i < max_iter && deadline.is_none_or(|d| Instant::now() < d) {
        let input = match &replay {
            Some(bytes) if i == 0 => bytes.clone(),
            Some(_) => break,
            None => input_at(config, &h, i),
        };
        std::fs::write(&flight_bin, &input)
            .and_then(|()| std::fs::write(&flight_txt, format!("{} {i}\n", target.name())))
            .map_err(|e| format!("{}: {e}", flight_bin.display()))?;
        tally.iterations += 1;
        match guarded(target, &h.dir, &input, config.per_input) {
            Verdict::Ran(Ran::Done(results)) => {
                tally.inputs += results.len() as u64;
                for r in results {
                    tally.ok += r.is_ok() as u64;
                    if let Err(e) = r {
                        let first = e.lines().next().unwrap_or_default().to_string();
                        if replay.is_some() {
                            println!("error: {first}");
                        }
                        tally.errors.insert(first);
                    }
                }
            }
            Verdict::Ran(Ran::Skipped(why)) => *tally.skipped.entry(why).or_default() += 1,
            Verdict::Panicked(msg) => {
                tally.inputs += 1;
                tally.crashes += 1;
                crashes.push(report(config, target, i, "panic", &msg, &input));
            }
            Verdict::Hung => {
                tally.inputs += 1;
                tally.crashes += 1;
                let msg = format!("no result within {} ms", config.per_input.as_millis());
                crashes.push(report(config, target, i, "hang", &msg, &input));
                stop = true;
                break;
            }
        }
        i += 1;
    }
    println!(
        "fuzz {:<5} seed {}: {} inputs run ({} ok), {} iterations, {} skipped by the guard, {} distinct \
         errors, {} crashes ({:.1} s)",
        target.name(),
        config.seed,
        tally.inputs,
        tally.ok,
        tally.iterations,
        tally.skipped.values().sum::<u64>(),
        tally.errors.len(),
        tally.crashes,
        t0.elapsed().as_secs_f64()
    );
    for (why, n) in &tally.skipped {
        println!("  skipped {n}: {why}");
    }
    Ok((crashes, stop))
}

/// Runs the fuzzing in this process (the child's part). `Ok(true)` when there were crashes.
pub fn run_worker(config: &Config) -> Result<bool, String> {
    install_panic_hook();
    if config.replay.is_some() && config.targets.len() != 1 {
        return Err("--replay needs one --target (scene, obj, exr or cli)".into());
    }
    std::fs::create_dir_all(&config.out).map_err(|e| format!("{}: {e}", config.out.display()))?;
    let start = Instant::now();
    let share = config
        .seconds
        .map(|s| Duration::from_secs_f64(s.max(0.0) / config.targets.len().max(1) as f64));
    let mut all = Vec::new();
    for (k, &target) in config.targets.iter().enumerate() {
        let deadline = share.map(|s| start + s * (k as u32 + 1));
        let (crashes, stop) = fuzz_target(config, target, deadline)?;
        all.extend(crashes);
        if stop {
            break;
        }
    }
    let (bin, txt) = inflight(&config.out);
    let _ = std::fs::remove_file(bin);
    let _ = std::fs::remove_file(txt);
    if !all.is_empty() {
        println!("{} crash(es):", all.len());
        for c in &all {
            println!("  {} {}: {}", c.kind, c.file.display(), c.message);
        }
    }
    Ok(!all.is_empty())
}

/// Exit status of the child when it found crashes (a hang ends it at once with this too).
pub const CRASH_STATUS: i32 = 1;

/// The parent's part: runs the worker as a child process (`args` plus `--worker`) and, when
/// the child dies without reporting (an abort), reports the input it was running.
/// `Ok(true)` when there were crashes.
pub fn run_supervised(config: &Config, args: &[String]) -> Result<bool, String> {
    std::fs::create_dir_all(&config.out).map_err(|e| format!("{}: {e}", config.out.display()))?;
    let (bin, txt) = inflight(&config.out);
    let _ = std::fs::remove_file(&bin);
    let _ = std::fs::remove_file(&txt);
    let exe = std::env::current_exe().map_err(|e| format!("cannot find the xtask binary: {e}"))?;
    let status = std::process::Command::new(exe)
        .args(args)
        .arg("--worker")
        .status()
        .map_err(|e| format!("cannot start the fuzz worker: {e}"))?;
    match status.code() {
        Some(0) => Ok(false),
        Some(CRASH_STATUS) => Ok(true),
        Some(2) => Err("the fuzz worker failed (see its error above)".into()),
        // Ctrl-C reached the worker too; not a crash of the input it was running.
        Some(sss_cli::INTERRUPTED_STATUS) => Err("the fuzz worker was interrupted".into()),
        _ => {
            let what = std::fs::read_to_string(&txt).unwrap_or_default();
            let mut parts = what.split_whitespace();
            let (Some(name), Some(iteration)) = (parts.next(), parts.next()) else {
                return Err(format!(
                    "the fuzz worker failed ({status}) before running an input"
                ));
            };
            let target = Target::ALL
                .into_iter()
                .find(|t| t.name() == name)
                .ok_or_else(|| format!("the fuzz worker failed ({status})"))?;
            let input = std::fs::read(&bin).unwrap_or_default();
            let iteration = iteration.parse().unwrap_or(0);
            report(
                config,
                target,
                iteration,
                "abort",
                &format!("the worker process died ({status})"),
                &input,
            );
            Ok(true)
        }
    }
}
