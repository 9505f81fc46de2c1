#!/usr/bin/env bash
# Coverage-guided fuzzing of the toolkit's readers with cargo-fuzz (libFuzzer), on nightly Rust.
#
#   bash fuzz/run.sh [SECONDS_PER_TARGET] [TARGET...]     (default: 30 s, every target)
#
# Builds every target of fuzz/Cargo.toml (`cargo +nightly fuzz build -O`: release, with the
# debug assertions and overflow checks that fuzz/Cargo.toml's profile turns on, no sanitizer:
# the code the targets reach is safe Rust, the readers, not the screen-space pass's SIMD, and an
# address sanitizer would slow every execution), then runs each for SECONDS_PER_TARGET with
# its dictionary (fuzz/dicts/TARGET.dict) and its committed seed corpus (fuzz/corpus/TARGET,
# read only): the new inputs it finds go to a scratch corpus, fuzz/scratch/corpus/TARGET (kept
# between runs, never committed), crashes to fuzz/scratch/artifacts/TARGET/. Prints per target
# the executions, executions per second, libFuzzer's final coverage (`cov:` edges, `ft:`
# features) and the crashes; exits 1 if any target crashed, naming each crashing input.
#
# Re-run one input: fuzz/target/x86_64-unknown-linux-gnu/release/TARGET PATH
# Environment: SSS_FUZZ_SANITIZER (default none; e.g. address), SSS_FUZZ_NICE (default 15).
set -u
cd "$(dirname "$0")/.."
seconds=${1:-30}
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
    targets=(scene_toml obj exr kernel_json shard_manifest)
fi
case $seconds in
    '' | *[!0-9]*) echo "usage: bash fuzz/run.sh [SECONDS_PER_TARGET] [TARGET...]" >&2; exit 2 ;;
esac
sanitizer=${SSS_FUZZ_SANITIZER:-none}
nice_level=${SSS_FUZZ_NICE:-15}
triple=x86_64-unknown-linux-gnu
bin_dir=fuzz/target/$triple/release
scratch=fuzz/scratch

echo "== building the fuzz targets (cargo +nightly fuzz build, sanitizer $sanitizer)"
if ! nice -n "$nice_level" cargo +nightly fuzz build --fuzz-dir fuzz -O -s "$sanitizer" \
    --target "$triple"; then
    echo "fuzz: the build failed" >&2
    exit 2
fi

# The targets write the files an input becomes here (memory when /dev/shm exists).
tmp_base=/dev/shm
[ -d "$tmp_base" ] || tmp_base=${TMPDIR:-/tmp}
export SSS_FUZZ_TMP
SSS_FUZZ_TMP=$(mktemp -d "$tmp_base/sss-fuzz.XXXXXX")
trap 'rm -rf "$SSS_FUZZ_TMP"' EXIT

crashed=0
summary=()
for t in "${targets[@]}"; do
    if [ ! -x "$bin_dir/$t" ]; then
        echo "fuzz: no target $t (built: $(ls "$bin_dir" 2>/dev/null | tr '\n' ' '))" >&2
        exit 2
    fi
    corpus=$scratch/corpus/$t
    artifacts=$scratch/artifacts/$t
    log=$scratch/logs/$t.log
    mkdir -p "$corpus" "$artifacts" "$scratch/logs"
    before=$(ls "$artifacts" | wc -l)
    echo "== $t: $seconds s"
    # The first corpus directory receives the new inputs; the committed seeds are only read.
    nice -n "$nice_level" "$bin_dir/$t" "$corpus" "fuzz/corpus/$t" \
        -dict="fuzz/dicts/$t.dict" -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 \
        -artifact_prefix="$artifacts/" -print_final_stats=1 >"$log" 2>&1
    rc=$?
    execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
    last=$(grep -E '^#[0-9]+.*cov: [0-9]+' "$log" | tail -1)
    cov=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")
    ft=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")
    new=$(ls "$artifacts" | wc -l)
    crashes=$((new - before))
    line=$(printf '%-15s execs %10s  exec/s %7s  cov %6s  ft %7s  crashes %s' \
        "$t" "${execs:-?}" "${rate:-?}" "${cov:-?}" "${ft:-?}" "$crashes")
    echo "$line"
    summary+=("$line")
    if [ "$rc" -ne 0 ] || [ "$crashes" -gt 0 ]; then
        crashed=1
        grep -E 'panicked at|ERROR: libFuzzer|ALARM|out-of-memory' "$log" | head -5
        for f in $(ls -t "$artifacts" | head -n "$((crashes > 0 ? crashes : 1))"); do
            echo "  crashing input: $artifacts/$f"
        done
        echo "  log: $log (rc $rc)"
    fi
done

echo "== summary ($seconds s per target)"
printf '%s\n' "${summary[@]}"
if [ "$crashed" -ne 0 ]; then
    echo "fuzz: a target crashed (inputs above); re-run one with $bin_dir/TARGET PATH" >&2
    exit 1
fi
