"""Renders against `sss render`'s EXR files, diff against `sss diff`, progress and stopping."""

import os
import signal
import subprocess
import threading
import time

import numpy as np
import pytest

import sss
from conftest import SKIN_SCENE, SMALL_SCENE


@pytest.mark.parametrize(
    "method,opts,cli",
    [
        ("exact", {}, []),
        ("pathtrace", {"spp": 4}, ["--spp", 4]),
        ("separable", {"kernel": "svd3", "uniform_taps": True}, ["--kernel", "svd3", "--uniform-taps"]),
    ],
)
def test_render_equals_sss_render_exr(method, opts, cli, small_scene, run_sss, tmp_path):
    exr = tmp_path / "out.exr"
    run_sss("render", small_scene, "--method", method, "--seed", 5, *cli, "--out", exr)
    expected = sss.read_exr(exr)
    out = sss.render(str(small_scene), method, seed=5, **opts)
    assert out["method"] == method
    assert out["total"].shape == (18, 24, 3) and out["total"].dtype == np.float32
    for layer in ["total", "subsurface"] + (["std_error"] if method == "pathtrace" else []):
        np.testing.assert_array_equal(out[layer], expected[layer], err_msg=layer)
    assert ("std_error" in out) == (method == "pathtrace")
    assert np.any(out["subsurface"] > 0)
    # The background and the opaque sphere are in the total only.
    assert np.any(out["total"] > out["subsurface"] + 1e-3)
    assert out["coverage"].shape == (18, 24) and out["coverage"].max() == 1.0
    # The silhouette of both spheres, as the EXR's alpha channel holds it.
    np.testing.assert_array_equal(out["alpha"], expected["alpha"])
    assert out["alpha"].shape == (18, 24) and np.all(out["alpha"] >= out["coverage"])
    assert out["alpha"].min() == 0.0 and np.any((out["alpha"] == 1.0) & (out["coverage"] == 0.0))
    assert "shading" in out["stages"] and all(v >= 0 for v in out["stages"].values())


#: A 1 m skin sphere seen close up: the camera sees a patch a few cm across.
BIG_SPHERE = """
[camera]
position = [0.0, 0.0, 1.15]
target = [0.0, 0.0, 0.0]
up = [0.0, 1.0, 0.0]
fov = 20.0
resolution = [16, 12]

[[lights]]
type = "point"
position = [0.5, 1.0, 2.0]
intensity = 5.0

[materials.skin]
type = "translucent"
model = "better-dipole"
preset = "skin1"
units_per_mm = 0.001

[[objects]]
material = "skin"
shape = "sphere"
radius = 1.0
"""


def test_irradiance_samples_only_where_seen_as_the_cli_reports(sss_bin, tmp_path):
    scene = tmp_path / "big.toml"
    scene.write_text(BIG_SPHERE)
    cli = subprocess.run([str(sss_bin), "render", str(scene), "--method", "dual-tree-fmm",
                          "--spacing", "4"], capture_output=True, text=True)
    assert cli.returncode == 0, cli.stderr
    line = next(l for l in cli.stdout.splitlines() if l.startswith("irradiance samples:"))
    out = sss.render(BIG_SPHERE, "dual-tree-fmm", spacing=4)
    assert out["irradiance_left_out"] > 100 * out["irradiance_samples"] > 0, out
    assert line == (f"irradiance samples: {out['irradiance_samples']} (about "
                    f"{out['irradiance_left_out']} more left out: beyond the profile's reach "
                    "of every visible point)"), line


def test_scene_as_text_path_or_builtin_name(small_scene, run_sss, tmp_path):
    a = sss.render(SMALL_SCENE, "pathtrace", spp=2)
    b = sss.render(small_scene, "pathtrace", spp=2)  # a pathlib.Path
    np.testing.assert_array_equal(a["total"], b["total"])
    # A built-in scene by name, with the method's screen-space layers (as --gbuffer writes).
    g = tmp_path / "g.exr"
    run_sss("render", "sphere", "--method", "separable", "--gbuffer", g)
    out = sss.render("sphere", "separable")
    layers = sss.read_exr(g)
    for name in ["irradiance", "surface"]:
        np.testing.assert_array_equal(out[name], layers[name], err_msg=name)
    assert out["total"].shape == (120, 160, 3)


def test_threads_do_not_change_the_image(small_scene):
    one = sss.render(small_scene, "pathtrace", spp=2, threads=1)
    two = sss.render(small_scene, "pathtrace", spp=2, threads=2)
    np.testing.assert_array_equal(one["total"], two["total"])


def parse_diff(text):
    out = {}
    for line in text.splitlines():
        k, *v = line.split()
        out[k] = [float(x) for x in v]
    return out


def test_diff_equals_sss_diff(small_scene, run_sss, tmp_path):
    a, b = tmp_path / "a.exr", tmp_path / "b.exr"
    run_sss("render", small_scene, "--method", "pathtrace", "--spp", 1, "--out", a)
    run_sss("render", small_scene, "--method", "exact", "--out", b)
    for layer in ["subsurface", "total"]:
        expected = parse_diff(run_sss("diff", a, b, "--layer", layer, "--eps", 0.1))
        for got in [
            sss.diff(a, b, layer=layer, eps=0.1),
            sss.diff(sss.read_exr(a)[layer], sss.read_exr(b)[layer], eps=0.1),
            sss.diff(sss.read_exr(a)[layer].astype(np.float64), str(b), layer=layer, eps=0.1),
        ]:
            assert got["pixels"] == expected["pixels"][0]
            # `sss diff` prints 6 significant digits (4 decimals for the fraction, 5 for ratios).
            np.testing.assert_allclose(got["rmse"], expected["rmse"][0], rtol=1e-5)
            np.testing.assert_allclose(got["rel_rmse"], expected["rel_rmse"][0], rtol=1e-5)
            np.testing.assert_allclose(got["frac_within_eps"], expected["frac_within_0.1"][0], atol=5e-5)
            np.testing.assert_allclose(got["mean_ratio"], expected["mean_ratio"], atol=5e-6)
            np.testing.assert_allclose(got["flip"], expected["flip"][0], atol=5e-7)
        assert expected["rmse"][0] > 0 and expected["flip"][0] > 0
    # Each side its own layer: `total` of a against `subsurface` of b, as `sss diff` does.
    expected = parse_diff(run_sss("diff", a, b, "--layer", "total", "--reference-layer", "subsurface"))
    got = sss.diff(a, b, layer="total", reference_layer="subsurface")
    assert got["pixels"] == expected["pixels"][0]
    np.testing.assert_allclose(got["rmse"], expected["rmse"][0], rtol=1e-5)
    same = sss.diff(sss.read_exr(a)["total"], sss.read_exr(b)["subsurface"])
    np.testing.assert_allclose(got["rmse"], same["rmse"], rtol=1e-12)


def test_diff_of_an_image_with_itself_is_zero():
    img = np.random.default_rng(1).random((5, 7, 3)).astype(np.float32)
    d = sss.diff(img, img)
    assert d["pixels"] == 35 and d["rmse"] == 0 and d["frac_within_eps"] == 1 and d["flip"] == 0
    np.testing.assert_array_equal(d["mean_ratio"], [1, 1, 1])


# A render of several seconds (the built-in sphere, path traced with many samples), to stop.
LONG = dict(scene="sphere", method="pathtrace", spp=64)


def test_progress_reports_the_shaded_samples():
    # Only the skin sphere: every camera sample that hits is translucent.
    seen = []
    out = sss.render(SKIN_SCENE, "exact", progress=lambda d, t: seen.append((d, t)))
    assert seen, "the callback was never called"
    done, total = seen[-1]
    # One camera sample per pixel; the samples that hit the sphere are shaded, once each.
    assert done == total == (out["coverage"] > 0).sum() > 0
    assert all(d <= t for d, t in seen)


def test_a_raising_callback_stops_the_render_and_the_next_render_is_right(small_scene):
    class Stop(Exception):
        pass

    calls = []

    def cb(done, total):
        calls.append((done, total))
        raise Stop("user stop")

    t = time.perf_counter()
    with pytest.raises(Stop, match="user stop"):
        sss.render(LONG["scene"], LONG["method"], spp=LONG["spp"], progress=cb)
    stopped_after = time.perf_counter() - t
    assert len(calls) == 1
    # The full render takes far longer; stopping takes at most a few polls.
    t = time.perf_counter()
    full = sss.render(LONG["scene"], LONG["method"], spp=LONG["spp"])
    full_time = time.perf_counter() - t
    assert stopped_after < 0.5 * full_time, (stopped_after, full_time)
    # Nothing was left half-done: a render after the stop equals a fresh one.
    again = sss.render(small_scene, "pathtrace", spp=2)
    np.testing.assert_array_equal(again["total"], sss.render(small_scene, "pathtrace", spp=2)["total"])
    assert np.any(full["subsurface"] > 0)


def test_ctrl_c_raises_keyboard_interrupt_during_a_render():
    # SIGINT arrives while the render runs with the GIL released; the main thread must notice
    # it within a poll, not when the render ends. Python's own handler is installed first: a
    # process started in the background by a non-interactive shell inherits SIGINT ignored,
    # and Python then leaves it ignored (no KeyboardInterrupt at all).
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    t = time.perf_counter()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            sss.render(LONG["scene"], LONG["method"], spp=4 * LONG["spp"])
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    assert time.perf_counter() - t < 3.0


# Every method whose render lasts more than a moment (separable filters the whole frame in
# a fraction of a second), at a resolution where each takes several seconds on 2 cores.
STOPPABLE = [(m, {}) for m in ["exact", "pathtrace", "single-tree", "dual-tree", "dual-tree-fmm",
                                 "manylight", "sparse-manylight", "mdlc", "eelc"]]
STOPPABLE.append(("volpath", {"boundary": "lambertian"}))  # the sphere has a point light


@pytest.mark.parametrize("method,opts", STOPPABLE)
def test_ctrl_c_stops_every_method_within_a_second(method, opts):
    # Each method checks for a stop as every unit of its work (a G-buffer sample, a pixel, a
    # tree's slice) starts, not as it ends: a unit that costs milliseconds, once per rayon
    # task, had kept `exact` running for 7-14 s after Ctrl-C.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    sent = []
    timer = threading.Timer(0.5, lambda: (sent.append(time.perf_counter()),
                                          os.kill(os.getpid(), signal.SIGINT)))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            sss.render("sphere", method, resolution=(640, 480), **opts)
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    assert sent, "the render ended before the signal"
    assert time.perf_counter() - sent[0] < 1.0, time.perf_counter() - sent[0]


def test_long_calls_release_the_gil():
    # A Python thread keeps ticking (every millisecond) while the render and the Monte Carlo
    # walk run: with the GIL held for the whole call it could not tick until the call returned.
    # Each call is repeated until half a second has passed, so that a fast machine still gives
    # a long enough window (between calls the GIL is free anyway, but only for microseconds:
    # a call that held it would leave about one tick per call).
    for call in [
        lambda: sss.render(LONG["scene"], LONG["method"], spp=LONG["spp"]),
        lambda: sss.monte_carlo(preset="skin1", r_max=4.0, bins=20, photons=500_000),
    ]:
        ticks = []
        stop = threading.Event()

        def tick():
            while not stop.is_set():
                ticks.append(time.perf_counter())
                time.sleep(0.001)

        t = threading.Thread(target=tick)
        t.start()
        while not ticks:
            time.sleep(0.001)
        start = time.perf_counter()
        calls = 0
        try:
            while calls == 0 or time.perf_counter() - start < 0.5:
                call()
                calls += 1
        finally:
            end = time.perf_counter()
            stop.set()
            t.join()
        assert end - start > 0.3, "the call is too short to tell"
        assert calls < 50, calls
        during = [x for x in ticks if start < x < end]
        # About one tick per millisecond when the thread can run; demand a tenth of that.
        assert len(during) > 100 * (end - start), (len(during), end - start)


def test_resolution_and_pixel_samples_override_the_camera(small_scene):
    out = sss.render(small_scene, "pathtrace", spp=1, resolution=(6, 4), pixel_samples=2)
    assert out["total"].shape == (4, 6, 3)
    assert out["coverage"].shape == (4, 6)
    with pytest.raises(ValueError, match="resolution"):
        sss.render(small_scene, resolution=(0, 4))
    with pytest.raises(ValueError, match="pixel_samples"):
        sss.render(small_scene, pixel_samples=0)
