#!/usr/bin/env bash
# CI step for the GPU pass (crates/gpu): installs Mesa's software Vulkan driver (lavapipe) when
# it is missing and runs the GPU tests with an adapter required (SSS_REQUIRE_GPU=1: no adapter
# is a failure, not a skip), once on wgpu's Vulkan backend (lavapipe) and once on its GL
# backend (llvmpipe through EGL, from the same Mesa install). Run from the repository root, as
# root on a fresh machine, after `cargo test --workspace --release`: `bash crates/gpu/ci.sh`.
#
# `--workspace` with `--test` builds only these two test targets but resolves features as the
# workspace test step does, so that step's build of wgpu and everything else is reused; only
# sss-cli (and its `sss` binary, now with `--gpu`) is rebuilt, with the `gpu` feature.
set -euo pipefail
cd "$(dirname "$0")/../.."

if ! compgen -G "/usr/share/vulkan/icd.d/lvp_icd*.json" >/dev/null \
    || ! ldconfig -p | grep -q 'libvulkan\.so\.1'; then
    echo "== installing mesa-vulkan-drivers libvulkan1"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq mesa-vulkan-drivers libvulkan1 >/dev/null
fi

export SSS_REQUIRE_GPU=1
# Mesa's window-system code complains on stderr when there is no session directory.
export XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-$(mktemp -d)}"
tests=(--workspace --release --features sss-cli/gpu --test gpu_vs_cpu --test filter_gpu)
cargo test "${tests[@]}" --no-run
for backend in vulkan gl; do
    echo "== GPU tests, WGPU_BACKEND=$backend"
    WGPU_BACKEND=$backend cargo test "${tests[@]}"
done
