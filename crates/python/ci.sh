#!/usr/bin/env bash
# CI step of the Python bindings (crates/python, module `sss`): the abi3 wheel built by maturin,
# installed into a fresh virtual environment, and the pytest suite, which compares against the
# `sss` binary: $SSS_BIN, else target/release/sss (built by `cargo test --workspace --release`),
# else built here. The crate is a member of the root workspace, so the root's `cargo fmt --all`
# and `cargo clippy --workspace` check it.
#
# Run from anywhere: bash crates/python/ci.sh. Cargo builds go to $CARGO_TARGET_DIR, default
# the repository's target/: after `cargo test --workspace --release` the wheel's build compiles
# only PyO3, numpy and the bindings themselves (same workspace, same features, same profile;
# PYO3_BUILD_EXTENSION_MODULE is set by .cargo/config.toml as maturin sets it).
set -euo pipefail
cd "$(dirname "$0")/../.."

export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$PWD/target}"
export PYTHONDONTWRITEBYTECODE=1
manifest=crates/python/Cargo.toml
python="${PYTHON:-python3}"
venv=target/pybind-venv
wheels=target/pybind-wheels

sss="${SSS_BIN:-target/release/sss}"
if [ ! -x "$sss" ]; then
    echo "== python bindings: building the sss binary to compare against"
    cargo build --release -p sss-cli
    sss="$CARGO_TARGET_DIR/release/sss"
fi
case "$sss" in
    /*) ;;
    *) sss="$PWD/$sss" ;;
esac
export SSS_BIN="$sss"

echo "== python bindings: fresh virtual environment"
rm -rf "$venv" "$wheels"
if ! "$python" -m venv "$venv"; then
    rm -rf "$venv"
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
        apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-venv
        "$python" -m venv "$venv"
    else
        echo "error: '$python -m venv $venv' failed; install the venv module" >&2
        exit 1
    fi
fi
"$venv/bin/pip" install --quiet --disable-pip-version-check \
    maturin==1.16.0 pytest==9.2.0 numpy==2.4.6

echo "== python bindings: abi3 wheel (maturin, release)"
start=$(date +%s)
"$venv/bin/maturin" build --release --manifest-path "$manifest" \
    --interpreter "$venv/bin/python" --out "$wheels"
echo "wheel built in $(($(date +%s) - start)) s"
"$venv/bin/pip" install --quiet --disable-pip-version-check "$wheels"/sss-*.whl

echo "== python bindings: pytest"
cd crates/python
# Import the installed wheel, not anything from the source tree.
"../../$venv/bin/python" -m pytest -q -p no:cacheprovider tests
echo "== python bindings: the example script (matplotlib not installed: no figures)"
"../../$venv/bin/python" examples/profiles_and_render.py "../../target/pybind-example"
