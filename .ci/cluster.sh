#!/usr/bin/env bash
# The cluster routes of docs/cluster run for real on this machine, each checked against an
# unsharded `cargo xtask compare` run of the same options (docs/cluster/README.md):
#
#   slurm   a single-node Slurm (docs/cluster/slurm/local-cluster.sh start: as root, on Debian),
#           docs/cluster/slurm/submit.sh N OPTIONS (a prepare job, an array of N shards, a
#           merge job); every job must succeed (a failed one's log is printed).
#   openjd  `openjd run docs/cluster/openjd/compare.yaml` (Prepare, N Shards tasks, Merge).
#
# Then docs/cluster/same-results.py: the merged results.csv equals UNSHARDED_DIR's in every
# column but the times (and profiles.csv, kernels.csv in their error columns).
#
#   .ci/cluster.sh UNSHARDED_DIR N [compare options...]
#
# UNSHARDED_DIR: the output of `xtask compare OPTIONS --out UNSHARDED_DIR`, the same options.
# Environment:
#   SSS_CLUSTER_PARTS    the parts to run [default: slurm openjd]
#   SSS_CLUSTER_OUT      where the routes write (slurm/ and openjd/ under it, emptied first)
#                        [default: target/cluster-ci]
#   SSS_CLUSTER_CACHE    a reference cache for both routes, e.g. the unsharded run's --cache
#                        (then the prepare steps only check it) [default: each route its own]
#   SSS_CLUSTER_TIMEOUT  seconds the Slurm jobs may take in all [default: 3600]
#   SSS_CLUSTER_SUBSET   1: UNSHARDED_DIR ran fewer scenes/presets; its rows must be in the
#                        merged output (how CI checks its full sharded run against a small one)
#   OPENJD               the openjd command [default: openjd on PATH, else
#                        target/ci-openjd/bin/openjd]
set -euo pipefail

if [[ $# -lt 2 || ! $2 =~ ^[1-9][0-9]*$ ]]; then
    echo "usage: $0 UNSHARDED_DIR N [compare options...]" >&2
    exit 2
fi
unsharded=$(cd "$1" && pwd) || { echo "error: no directory $1" >&2; exit 2; }
n=$2
shift 2
[[ -s $unsharded/results.csv ]] || { echo "error: no $unsharded/results.csv" >&2; exit 2; }
root=$(cd "$(dirname "$0")/.." && pwd)
out=${SSS_CLUSTER_OUT:-$root/target/cluster-ci}
mkdir -p "$out"
out=$(cd "$out" && pwd)
cache=${SSS_CLUSTER_CACHE:-}
[[ -z $cache ]] || { mkdir -p "$cache" && cache=$(cd "$cache" && pwd); }
parts=${SSS_CLUSTER_PARTS:-slurm openjd}
same_results=(python3 "$root/docs/cluster/same-results.py")
# SSS_CLUSTER_SUBSET=1: UNSHARDED_DIR is a run of fewer scenes or presets than OPTIONS ask for,
# whose every row the merged output must hold (same-results.py --subset).
[[ ${SSS_CLUSTER_SUBSET:-} != 1 ]] || same_results+=(--subset)

say() { echo "cluster: $*"; }
fail() {
    echo "cluster: FAILED: $*" >&2
    exit 1
}

# Seconds since the epoch of a Slurm time stamp (2024-01-02T03:04:05).
epoch() { date -d "$1" +%s 2>/dev/null || echo 0; }

# The field NAME of a line of `scontrol show job -o`.
field() {
    local re="(^| )$1=([^ ]*)"
    if [[ $2 =~ $re ]]; then echo "${BASH_REMATCH[2]}"; fi
}

slurm_part() {
    local t0=$SECONDS
    bash "$root/docs/cluster/slurm/local-cluster.sh" start
    local t_cluster=$((SECONDS - t0))
    local dir=$out/slurm
    rm -rf "$dir"
    export SSS_CLUSTER_OUT=$dir
    if [[ -n $cache ]]; then export SSS_CLUSTER_CACHE=$cache; else unset SSS_CLUSTER_CACHE; fi
    local t1=$SECONDS
    bash "$root/docs/cluster/slurm/submit.sh" "$n" "$@"
    local prepare shards merge
    prepare=$(awk '$1 == "prepare" {print $2}' "$dir/jobs.txt")
    shards=$(awk '$1 == "shards" {print $2}' "$dir/jobs.txt")
    merge=$(awk '$1 == "merge" {print $2}' "$dir/jobs.txt")
    local ids=("$prepare" "$shards" "$merge")
    local deadline=$((SECONDS + ${SSS_CLUSTER_TIMEOUT:-3600})) last="" lines summary
    local line id task state reason name done=""
    while :; do
        lines=""
        for id in "${ids[@]}"; do
            lines+=$(scontrol show job -o "$id" 2>/dev/null ||
                echo "JobId=$id JobName=? JobState=GONE")
            lines+=$'\n'
        done
        summary="" done=""
        local failed=()
        while read -r line; do
            [[ -n $line ]] || continue
            id=$(field JobId "$line")
            task=$(field ArrayTaskId "$line")
            name=$(field JobName "$line")
            state=$(field JobState "$line")
            reason=$(field Reason "$line")
            summary+=" ${name#sss-}${task:+[$task]}=$state"
            [[ $state == PENDING && $reason != None ]] && summary+="($reason)"
            case $state in
                COMPLETED) [[ $id == "$merge" ]] && done=yes ;;
                PENDING | CONFIGURING | RUNNING | COMPLETING | SUSPENDED) ;;
                GONE) [[ $id == "$merge" ]] && done=gone ;;
                *) failed+=("$line") ;;
            esac
            if [[ $state == PENDING && $reason == DependencyNeverSatisfied ]]; then
                failed+=("$line")
            fi
        done <<<"$lines"
        if [[ $summary != "$last" ]]; then
            say "$((SECONDS - t1)) s:$summary"
            last=$summary
        fi
        if [[ ${#failed[@]} -gt 0 ]]; then
            for line in "${failed[@]}"; do
                echo "cluster: job $(field JobId "$line") ($(field JobName "$line")$(
                    task=$(field ArrayTaskId "$line"); [[ -n $task ]] && echo " $task"
                )): $(field JobState "$line"), reason $(field Reason "$line"), exit code $(
                    field ExitCode "$line")" >&2
                local log
                log=$(field StdOut "$line")
                if [[ -s $log ]]; then
                    echo "----- $log" >&2
                    tail -40 "$log" >&2
                    echo "-----" >&2
                fi
            done
            scancel "${ids[@]}" 2>/dev/null || true
            fail "a Slurm job did not succeed (logs in $dir/logs)"
        fi
        [[ -z $done ]] || break
        if [[ $SECONDS -gt $deadline ]]; then
            scancel "${ids[@]}" 2>/dev/null || true
            fail "the Slurm jobs took over ${SSS_CLUSTER_TIMEOUT:-3600} s; cancelled"
        fi
        sleep 2
    done
    local t_jobs=$((SECONDS - t1))
    # Each job's time from Slurm's start and end stamps (known for MinJobAge after the end).
    local times="" first=0 end=0 s e
    while read -r line; do
        [[ -n $line ]] || continue
        s=$(epoch "$(field StartTime "$line")")
        e=$(epoch "$(field EndTime "$line")")
        name=$(field JobName "$line")
        task=$(field ArrayTaskId "$line")
        times+=" ${name#sss-}${task:+[$task]} $((e - s)) s,"
        if [[ $name == sss-shard ]]; then
            [[ $first -eq 0 || $s -lt $first ]] && first=$s
            [[ $e -gt $end ]] && end=$e
        fi
    done <<<"$(for id in "${ids[@]}"; do scontrol show job -o "$id" 2>/dev/null || true; done)"
    if [[ $done == gone ]]; then
        say "the jobs left scontrol before they were checked: judging by the output"
    fi
    [[ -s $dir/merged/results.csv ]] || fail "no $dir/merged/results.csv (logs in $dir/logs)"
    "${same_results[@]}" "$unsharded" "$dir/merged" || fail "the Slurm route's results differ"
    say "slurm: cluster up in $t_cluster s, jobs done in $t_jobs s:${times%,}; shards" \
        "$((end - first)) s from the first start to the last end"
}

openjd_part() {
    local cmd=${OPENJD:-}
    if [[ -z $cmd ]]; then
        if command -v openjd >/dev/null; then
            cmd=openjd
        elif [[ -x $root/target/ci-openjd/bin/openjd ]]; then
            cmd=$root/target/ci-openjd/bin/openjd
        else
            fail "no openjd: python3 -m venv target/ci-openjd &&" \
                "target/ci-openjd/bin/pip install openjd-cli==0.8.0 (or set OPENJD)"
        fi
    fi
    local dir=$out/openjd quick=false opts=() o
    for o in "$@"; do
        if [[ $o == --quick ]]; then quick=true; else opts+=("$o"); fi
    done
    rm -rf "$dir"
    mkdir -p "$dir"
    local params=(-p "Workspace=$root" -p "Output=$dir" -p "ShardCount=$n" -p "Quick=$quick"
        -p "Options=${opts[*]}")
    [[ -z $cache ]] || params+=(-p "Cache=$cache")
    say "openjd run docs/cluster/openjd/compare.yaml --step Merge --run-dependencies" \
        "${params[*]}"
    local t0=$SECONDS
    if ! "$cmd" run "$root/docs/cluster/openjd/compare.yaml" --step Merge --run-dependencies \
        --timestamp-format relative "${params[@]}" >"$dir/openjd.log" 2>&1; then
        tail -60 "$dir/openjd.log" >&2
        fail "openjd run failed (log: $dir/openjd.log)"
    fi
    local t_run=$((SECONDS - t0))
    [[ -s $dir/merged/results.csv ]] || {
        tail -60 "$dir/openjd.log" >&2
        fail "openjd run made no $dir/merged/results.csv (log: $dir/openjd.log)"
    }
    "${same_results[@]}" "$unsharded" "$dir/merged" ||
        fail "the Open Job Description route's results differ"
    # Each step's time from the log's time stamps (H:MM:SS.ffffff from the session's start).
    local steps
    steps=$(awk -F'\t' '
        { split($1, t, ":"); now = t[1] * 3600 + t[2] * 60 + t[3] }
        $2 ~ /Running step / || $2 ~ /All actions completed/ {
            if (step != "") { printf "%s%s %.0f s", sep, step, now - start; sep = ", " }
            step = $2; sub(/.*Running step /, "", step); gsub(/\047/, "", step); start = now
        }' "$dir/openjd.log")
    say "openjd: done in $t_run s: $steps (log: $dir/openjd.log)"
}

for part in $parts; do
    case $part in
        slurm) slurm_part "$@" ;;
        openjd) openjd_part "$@" ;;
        *) fail "unknown part '$part' in SSS_CLUSTER_PARTS (slurm, openjd)" ;;
    esac
done
say "every route ($parts) gives the unsharded results"
