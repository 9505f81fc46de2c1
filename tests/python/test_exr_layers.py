"""An independent reader of `sss render --out`: the OpenEXR Python bindings (the classic
`OpenEXR.InputFile` API, which sees only a file's first part, and the newer `OpenEXR.File`)
must see every layer of the file, as `R,G,B` (the `total` layer) and `layer.R,G,B`.

Run by `tests/python/run.sh` (which makes the virtual environment). The files are rendered with
`target/release/sss` (or `$SSS_BIN`): two path-traced renders of the built-in `sphere` scene
(160x120) with seeds 1 and 2, so that they carry a `std_error` layer and differ. Set
`$SSS_EXR` to check a file of your own instead of the first render (the second is then the
same file).

The values the bindings read are checked against what `sss` itself reads from the same files
(`sss diff A B --layer L` prints, for layer L, the pixel count, the RMSE and the mean ratio,
computed here again from the bindings' arrays), and against what the layers mean, whoever
reads them: values finite and non-negative, total >= subsurface, subsurface on the sphere
and not in the corners, and `std_error` the spread of `subsurface` between the two seeds. A
layer written under another layer's name, or unreadable by the bindings, fails.
"""

import os
import re
import subprocess
from pathlib import Path

import Imath
import numpy as np
import OpenEXR
import pytest

REPO = Path(__file__).resolve().parents[2]
SSS = Path(os.environ.get("SSS_BIN", REPO / "target" / "release" / "sss"))
LAYERS = ["total", "subsurface", "std_error"]
WIDTH, HEIGHT = 160, 120


def channel_names(layer):
    """The channel names of `layer`: plain R, G, B for `total` (the first layer written)."""
    if layer == "total":
        return ["R", "G", "B"]
    return [f"{layer}.{c}" for c in "RGB"]


def run_sss(*args):
    if not SSS.is_file():
        pytest.fail(f"{SSS} is missing: build it with `cargo build --release -p sss-cli`")
    done = subprocess.run(
        [str(SSS), *map(str, args)], capture_output=True, text=True, timeout=600
    )
    assert done.returncode == 0, f"sss {' '.join(map(str, args))}: {done.stderr}"
    return done.stdout


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Two EXR files written by `sss render --out`: (A, B)."""
    given = os.environ.get("SSS_EXR")
    if given:
        return Path(given), Path(given)
    tmp = tmp_path_factory.mktemp("renders")
    out = []
    for seed in (1, 2):
        path = tmp / f"sphere{seed}.exr"
        run_sss(
            "render", "sphere", "--method", "pathtrace", "--spp", "2", "--seed", seed,
            "--threads", "2", "--out", path,
        )
        out.append(path)
    return tuple(out)


def read_old_api(path):
    """Every channel of `path` through `OpenEXR.InputFile`, as float64 arrays (h, w)."""
    exr = OpenEXR.InputFile(str(path))
    try:
        header = exr.header()
        window = header["dataWindow"]
        w, h = window.max.x - window.min.x + 1, window.max.y - window.min.y + 1
        names = sorted(header["channels"])
        raw = exr.channels(names, Imath.PixelType(Imath.PixelType.FLOAT))
    finally:
        exr.close()
    return header, {
        n: np.frombuffer(b, dtype=np.float32).reshape(h, w) for n, b in zip(names, raw)
    }


def layer(arrays, name):
    """Layer `name` as an (h, w, 3) float64 array."""
    return np.stack([arrays[c] for c in channel_names(name)], axis=-1).astype(np.float64)


def test_the_classic_api_sees_every_layer_in_one_part(files):
    header, arrays = read_old_api(files[0])
    channels = header["channels"]
    # Every layer's R, G, B and the beauty's alpha A.
    expected = {c for l in LAYERS for c in channel_names(l)} | {"A"}
    assert set(channels) == expected, sorted(channels)
    float_type = Imath.PixelType(Imath.PixelType.FLOAT)
    for name, ch in channels.items():
        assert ch.type == float_type, (name, ch.type)
    window = header["dataWindow"]
    assert (window.max.x - window.min.x + 1, window.max.y - window.min.y + 1) == (WIDTH, HEIGHT)
    # The beauty's layer name is the part's name.
    name = header.get("name")
    assert (name.decode() if isinstance(name, bytes) else name) == "total"
    for arr in arrays.values():
        assert arr.shape == (HEIGHT, WIDTH)
        assert np.all(np.isfinite(arr)) and np.all(arr >= 0.0)


def test_both_apis_read_the_same_bits(files):
    _, old = read_old_api(files[0])
    with OpenEXR.File(str(files[0]), separate_channels=True) as f:
        assert len(f.parts) == 1, "one part, not one per layer"
        new = f.parts[0].channels
        assert set(new) == set(old), (sorted(new), sorted(old))
        for name, arr in old.items():
            pixels = new[name].pixels
            assert pixels.dtype == np.float32, (name, pixels.dtype)
            assert np.array_equal(pixels.view(np.uint32), arr.view(np.uint32)), name


def test_layers_hold_what_their_names_say(files):
    _, arrays = read_old_api(files[0])
    total, sub, err = (layer(arrays, n) for n in LAYERS)
    # Total radiance includes the subsurface term; the sphere covers the centre, not the
    # corners (there is no ground and the background is black).
    assert np.all(total >= sub)
    centre = sub[HEIGHT // 2, WIDTH // 2]
    assert np.all(centre > 0.0), centre
    for y, x in [(0, 0), (0, WIDTH - 1), (HEIGHT - 1, 0), (HEIGHT - 1, WIDTH - 1)]:
        assert np.all(sub[y, x] == 0.0) and np.all(err[y, x] == 0.0), (y, x)
    assert np.any(err > 0.0)
    # The error bars of a 2-sample estimate are not the estimate itself.
    assert not np.array_equal(err, sub)
    # The alpha is the sphere's silhouette: 1 at the centre, 0 in the corners, positive
    # wherever there is subsurface light, a fraction of the camera samples in [0, 1].
    alpha = arrays["A"]
    assert alpha[HEIGHT // 2, WIDTH // 2] == 1.0
    for y, x in [(0, 0), (0, WIDTH - 1), (HEIGHT - 1, 0), (HEIGHT - 1, WIDTH - 1)]:
        assert alpha[y, x] == 0.0, (y, x)
    assert np.all((alpha >= 0.0) & (alpha <= 1.0))
    assert np.all(alpha[sub.max(axis=-1) > 0.0] > 0.0)
    assert 0.1 < alpha.mean() < 0.9, alpha.mean()


def test_std_error_is_the_spread_of_the_subsurface_estimate(files):
    """Independent of how `sss` reads its files: two renders with different seeds differ by
    about their error bars, mean (A - B)^2 = mean (se_A^2 + se_B^2) per channel (1.02 to 1.07
    for the two renders here). Swapping `subsurface` and `std_error` gives 0.1 to 0.2."""
    if files[0] == files[1]:
        pytest.skip("$SSS_EXR names one file; this needs two renders")
    a, b = (read_old_api(f)[1] for f in files)
    sub_a, sub_b = layer(a, "subsurface"), layer(b, "subsurface")
    se_a, se_b = layer(a, "std_error"), layer(b, "std_error")
    spread = ((sub_a - sub_b) ** 2).mean(axis=(0, 1))
    bars = (se_a**2 + se_b**2).mean(axis=(0, 1))
    assert np.all(bars > 0.0)
    ratio = spread / bars
    assert np.all((ratio > 0.7) & (ratio < 1.4)), ratio


def diff_figures(a, b):
    """`sss diff`'s figures of image `a` against reference `b` ((h, w, 3) arrays)."""
    a, b = a.reshape(-1, 3), b.reshape(-1, 3)
    pixels = np.any((a > 0.0) | (b > 0.0), axis=1)
    a, b = a[pixels], b[pixels]
    rmse = float(np.sqrt(np.mean((a - b) ** 2))) if len(a) else 0.0
    sa, sb = a.sum(axis=0), b.sum(axis=0)
    ratio = np.where(sb > 0.0, sa / np.where(sb > 0.0, sb, 1.0), 0.0)
    return int(pixels.sum()), rmse, ratio


@pytest.mark.parametrize("name", LAYERS)
def test_values_match_what_sss_reads_by_layer_name(files, name):
    a_path, b_path = files
    text = run_sss("diff", a_path, b_path, "--layer", name)
    figures = dict(line.split(maxsplit=1) for line in text.splitlines() if line.strip())
    pixels, rmse, ratio = diff_figures(
        layer(read_old_api(a_path)[1], name), layer(read_old_api(b_path)[1], name)
    )
    assert pixels > 0
    assert int(figures["pixels"]) == pixels, (name, figures["pixels"], pixels)
    assert float(figures["rmse"]) == pytest.approx(rmse, rel=1e-5, abs=1e-30), name
    printed = [float(v) for v in re.split(r"\s+", figures["mean_ratio"].strip())]
    assert printed == pytest.approx(list(ratio), abs=1.5e-5), name
