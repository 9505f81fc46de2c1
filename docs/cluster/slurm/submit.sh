#!/usr/bin/env bash
# Submits a sharded `cargo xtask compare` to Slurm: a prepare job, an array of N shard jobs
# after it (afterok), and a merge job after the whole array (afterok).
#
#   docs/cluster/slurm/submit.sh N [compare options...]
#
# Assumes the checkout, target/release/xtask, the meshes and SSS_CLUSTER_OUT (default
# target/cluster in the checkout) are on a filesystem every node sees (docs/cluster/README.md).
# The references are cached in SSS_CLUSTER_CACHE (default SSS_CLUSTER_OUT/cache): point it at
# the --cache of an earlier run with the same settings and the prepare job only checks it.
# Writes the three job ids to SSS_CLUSTER_OUT/jobs.txt (`prepare ID`, `shards ID`, `merge ID`).
set -euo pipefail
if [[ $# -lt 1 || ! $1 =~ ^[1-9][0-9]*$ ]]; then
    echo "usage: $0 N [compare options...]   (N shards, at least 1)" >&2
    exit 2
fi
n=$1
shift
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../../.." && pwd)"
out="${SSS_CLUSTER_OUT:-$root/target/cluster}"
cache="${SSS_CLUSTER_CACHE:-$out/cache}"
if [[ ! -x "$root/target/release/xtask" ]]; then
    echo "error: $root/target/release/xtask is missing: run 'cargo build --release -p xtask' first" >&2
    exit 2
fi
mkdir -p "$out/logs"
export SSS_ROOT="$root" SSS_CLUSTER_OUT="$out" SSS_CLUSTER_CACHE="$cache" SSS_SHARDS="$n"
prepare=$(sbatch --parsable --output="$out/logs/prepare-%j.log" \
    "$here/prepare.sbatch" "$@")
shards=$(sbatch --parsable --dependency="afterok:$prepare" --array="1-$n" \
    --output="$out/logs/shard-%a-%j.log" "$here/shard.sbatch" "$@")
merge=$(sbatch --parsable --dependency="afterok:$shards" \
    --output="$out/logs/merge-%j.log" "$here/merge.sbatch")
printf 'prepare %s\nshards %s\nmerge %s\n' "$prepare" "$shards" "$merge" >"$out/jobs.txt"
echo "prepare $prepare, shards $shards (array 1-$n), merge $merge -> $out/merged"
