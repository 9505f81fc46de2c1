#!/usr/bin/env bash
# Checks with an independent reader, the OpenEXR Python bindings, that every layer of the EXR
# files `sss render --out` writes is visible and holds what `sss` reads from it
# (tests/python/test_exr_layers.py). Builds nothing: it needs target/release/sss (or $SSS_BIN),
# from `cargo build --release -p sss-cli`. Makes a virtual environment at target/py-venv with
# the versions pinned in tests/python/requirements.txt (again when that file changes).
set -euo pipefail
cd "$(dirname "$0")/../.."

sss="${SSS_BIN:-target/release/sss}"
if [ ! -x "$sss" ]; then
    echo "error: $sss is missing; build it first: cargo build --release -p sss-cli" >&2
    exit 1
fi
case "$sss" in
    /*) ;;
    *) sss="$PWD/$sss" ;; # relative to the repository root
esac
export SSS_BIN="$sss"

python="${PYTHON:-python3}"
venv=target/py-venv
requirements=tests/python/requirements.txt
if [ ! -x "$venv/bin/python" ]; then
    rm -rf "$venv"
    if ! "$python" -m venv "$venv"; then
        rm -rf "$venv"
        # Debian and Ubuntu ship venv (ensurepip) separately.
        if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
            echo "== $python -m venv failed: installing python3-venv"
            apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3-venv
            "$python" -m venv "$venv"
        else
            echo "error: '$python -m venv $venv' failed; install the venv module" \
                "(Debian/Ubuntu: apt-get install python3-venv)" >&2
            exit 1
        fi
    fi
fi
if ! cmp -s "$requirements" "$venv/requirements.installed"; then
    "$venv/bin/python" -m pip install --quiet --disable-pip-version-check -r "$requirements"
    cp "$requirements" "$venv/requirements.installed"
fi

status=0
PYTHONDONTWRITEBYTECODE=1 "$venv/bin/python" -m pytest -q -p no:cacheprovider \
    tests/python/test_exr_layers.py "$@" || status=$?
if [ "$status" = 5 ]; then
    echo "error: pytest collected no tests" >&2
    exit 1
fi
exit "$status"
