#!/usr/bin/env bash
# Miri on the `unsafe` code of the screen-space pass (crates/separable/src/screen_space/avx2.rs
# and its callers): the unit tests of `screen_space::tests` run in Miri's interpreter, which
# checks every memory access they make (bounds, alignment, initialisation, aliasing under Tree
# Borrows) and executes the AVX2 and FMA intrinsics itself.
#
#   bash crates/separable/miri.sh          # about 20 minutes on 2 cores, the build included
#
# The build enables AVX2 and FMA (-C target-feature), so that `is_x86_feature_detected!` says
# yes under Miri and the chunks take the AVX2 loops (the test prints which loops ran); the
# tests shrink their frames and iteration counts under `cfg(miri)`. Tree Borrows instead of
# Stacked Borrows, and leaks ignored: rayon's crossbeam-epoch trips Stacked Borrows (a known
# report of that crate, not of this one), and rayon's pool threads outlive the test. Needs the
# nightly toolchain with the `miri` and `rust-src` components
# (`rustup component add --toolchain nightly miri rust-src`). Not run in CI (too slow for its
# budget): docs/testing.md has the last figures.
set -euo pipefail
cd "$(dirname "$0")/../.."
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$PWD/target/miri-separable}"
export RUSTFLAGS="-C target-feature=+avx2,+fma"
export MIRIFLAGS="-Zmiri-tree-borrows -Zmiri-permissive-provenance -Zmiri-ignore-leaks"
exec cargo +nightly miri test -p sss-separable --lib screen_space::tests -- --nocapture "$@"
