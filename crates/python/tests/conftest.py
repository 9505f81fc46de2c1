"""Shared fixtures: the `sss` binary the bindings are compared against, and small scenes.

The binary is $SSS_BIN, else target/release/sss, else target/pybind/release/sss under the
repository root. The tests fail (they do not skip) when none exists: the comparisons with the
command-line tool are the point of most of them.
"""

import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[3]

#: A 24x18 sphere of skin lit from the front and by a dim environment: small enough to render
#: in well under a second.
SKIN_SCENE = """
[camera]
position = [0.0, 0.0, 4.0]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov = 30.0
resolution = [24, 18]

[[lights]]
type = "directional"
direction = [0.0, 0.0, -1.0]
irradiance = 1.0

[[lights]]
type = "environment"
radiance = [0.05, 0.06, 0.08]

[materials.skin]
type = "translucent"
model = "better-dipole"
preset = "skin1"
units_per_mm = 0.1

[[objects]]
material = "skin"
shape = "sphere"
radius = 1.0
"""

#: SKIN_SCENE with an opaque sphere beside the skin: `total` differs from `subsurface` on it
#: and on the background.
SMALL_SCENE = SKIN_SCENE + """
[materials.clay]
type = "diffuse"
albedo = 0.6

[[objects]]
material = "clay"
shape = "sphere"
radius = 0.3
transform = { translate = [1.3, -0.5, 0.5] }
"""


def _find_binary() -> pathlib.Path | None:
    env = os.environ.get("SSS_BIN")
    if env:
        return pathlib.Path(env)
    for rel in ("target/release/sss", "target/pybind/release/sss"):
        p = REPO / rel
        if p.exists():
            return p
    return None


@pytest.fixture(scope="session")
def sss_bin() -> pathlib.Path:
    path = _find_binary()
    if path is None or not path.exists():
        pytest.fail(
            "no `sss` binary to compare against: build it (cargo build --release -p sss-cli) "
            "or set SSS_BIN"
        )
    return path


@pytest.fixture(scope="session")
def run_sss(sss_bin):
    """Runs `sss ARGS...` and returns its stdout; fails the test when it fails."""

    def run(*args, cwd=None) -> str:
        p = subprocess.run(
            [str(sss_bin), *map(str, args)], capture_output=True, text=True, cwd=cwd
        )
        assert p.returncode == 0, f"sss {' '.join(map(str, args))} failed: {p.stderr}"
        return p.stdout

    return run


@pytest.fixture(scope="session")
def sss_error(sss_bin):
    """Runs `sss ARGS...`, which must fail, and returns its message without `error: `."""

    def run(*args) -> str:
        p = subprocess.run([str(sss_bin), *map(str, args)], capture_output=True, text=True)
        assert p.returncode != 0, f"sss {' '.join(map(str, args))} unexpectedly succeeded"
        lines = [l for l in p.stderr.splitlines() if l.startswith("error: ")]
        assert len(lines) == 1, p.stderr
        return lines[0][len("error: ") :]

    return run


@pytest.fixture(scope="session")
def small_scene(tmp_path_factory) -> pathlib.Path:
    path = tmp_path_factory.mktemp("scenes") / "small.toml"
    path.write_text(SMALL_SCENE)
    return path
