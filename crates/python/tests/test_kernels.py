"""Kernels against `sss kernel`, and the screen-space filter against `sss filter`."""

import io

import numpy as np
import pytest

import sss

FORMATS = ["json", "csv", "glsl", "hlsl", "wgsl"]


def csv_taps(text: str):
    """`sss kernel --format csv` as {(term, direction): (N, 4) offset, r, g, b}."""
    out = {}
    for line in text.splitlines()[1:]:
        f = line.split(",")
        out.setdefault((int(f[0]), f[1]), []).append([float(x) for x in f[2:]])
    return {k: np.array(v) for k, v in out.items()}


@pytest.mark.parametrize(
    "method,extra,cli",
    [
        ("preintegrated", {}, []),
        ("guided", {"k": 1.5, "taps": 9}, ["--k", 1.5, "--taps", 9]),
        ("svd3", {"taps": 5}, ["--taps", 5]),
        ("artist", {"artist_preset": "production", "normalize": True}, ["--artist-preset", "production", "--normalize"]),
        ("gaussians1", {"uniform": True}, ["--uniform"]),
    ],
)
def test_exports_equal_sss_kernel(method, extra, cli, run_sss):
    model = sss.Model("better-dipole", preset="skin1")
    k = sss.kernel(model, method, **extra)
    for fmt in FORMATS:
        expected = run_sss(
            "kernel", "--preset", "skin1", "--model", "better-dipole", "--method", method,
            *cli, "--format", fmt,
        )
        assert k.export(fmt) == expected, fmt
    taps = csv_taps(run_sss("kernel", "--preset", "skin1", "--method", method, *cli, "--format", "csv"))
    if (0, "both") in taps:
        assert len(k.terms) == 1
        np.testing.assert_array_equal(k.taps, taps[(0, "both")])
    else:
        assert k.taps is None
        assert len(k.terms) == len(taps) // 2
        for i, (h, v) in enumerate(k.terms):
            np.testing.assert_array_equal(h, taps[(i, "horizontal")])
            np.testing.assert_array_equal(v, taps[(i, "vertical")])


def test_rank1_weights_sum_to_the_total_diffuse_reflectance():
    # The documented energy rule of `sss kernel`: a rank-1 kernel's weights sum to R per
    # channel (to 1 with normalize=True).
    for preset in ["skin1", "marble", "ketchup"]:
        m = sss.Model("pbd", preset=preset)
        k = sss.kernel(m, "preintegrated", taps=11)
        assert k.taps.shape == (11, 4)
        np.testing.assert_allclose(k.taps[:, 1:].sum(axis=0), m.total_diffuse_reflectance, rtol=1e-9)
        kn = sss.kernel(m, "preintegrated", taps=11, normalize=True)
        np.testing.assert_allclose(kn.taps[:, 1:].sum(axis=0), 1.0, rtol=1e-9)


def test_coefficient_media_export_like_the_cli(run_sss):
    m = sss.Model("standard-dipole", sigma_a=[0.03, 0.06, 0.2], sigma_s=[2.0, 1.5, 1.0], g=0.2, eta=1.33)
    expected = run_sss(
        "kernel", "--sigma-a", "0.03,0.06,0.2", "--sigma-s", "2,1.5,1", "--g", 0.2, "--eta", 1.33,
        "--model", "standard-dipole", "--format", "wgsl",
    )
    assert sss.kernel(m).export("wgsl") == expected


@pytest.fixture(scope="module")
def gbuffer(run_sss, tmp_path_factory):
    """The separable method's screen-space inputs of the built-in sphere, written by `sss`."""
    d = tmp_path_factory.mktemp("filter")
    g = d / "g.exr"
    run_sss("render", "sphere", "--method", "separable", "--gbuffer", g)
    return g


def inputs_of(path):
    layers = sss.read_exr(path)
    irr, surface = layers["irradiance"], layers["surface"]
    ids = np.rint(surface[..., 2]).astype(np.int32) - 1
    return irr, surface[..., 0].copy(), surface[..., 1].copy(), ids


@pytest.mark.parametrize(
    "kernel,cli",
    [("preintegrated", []), ("svd3", ["--kernel", "svd3", "--taps", 9]), ("exact2d", ["--kernel", "exact2d"])],
)
def test_filter_equals_sss_filter(kernel, cli, gbuffer, run_sss, tmp_path):
    # The built-in sphere's own scale (0.05 units per mm) and material (skin1, better dipole):
    # the kernel is a few pixels wide, so silhouettes and depth steps drop taps.
    out = tmp_path / "f.exr"
    run_sss(
        "filter", gbuffer, "--preset", "skin1", "--model", "better-dipole", "--units-per-mm", 0.05,
        "--seed", 3, *cli, "--out", out,
    )
    expected = sss.read_exr(out)["exitance"]
    irr, depth, footprint, ids = inputs_of(gbuffer)
    assert (ids >= 0).sum() > 1000
    kwargs = {"taps": 9} if kernel == "svd3" else {}
    got = sss.filter(
        irr, depth, footprint, ids, kernel, sss.Model("better-dipole", preset="skin1"),
        units_per_mm=0.05, seed=3, **kwargs,
    )
    assert got.shape == irr.shape and got.dtype == np.float32
    # The EXR writer stores negative values (signed SVD terms) as 0.
    np.testing.assert_array_equal(np.where(got > 0, got, 0), expected)
    assert np.any(expected > 0)


def test_filter_does_not_blur_across_a_depth_step_in_scene_units():
    # One object, lit on its right half only, in scene units of 10 m (units_per_mm = 1e-4).
    # The right half sits 0.1 kernel widths deeper in scene units, 1000 kernel widths in mm:
    # no light crosses to the left half. At one depth it does.
    h, w = 32, 64
    u = 1e-4
    m = sss.Model("better-dipole", preset="skin1")
    support = np.abs(sss.kernel(m, "preintegrated").taps[:, 0]).max()  # mm
    irr = np.zeros((h, w, 3), np.float32)
    irr[:, w // 2 :] = 1.0
    footprint = np.full((h, w), support / 8 * u, np.float32)  # the widest tap 8 pixels out
    ids = np.zeros((h, w), np.int32)
    flat = np.full((h, w), 1.0, np.float32)
    step = flat.copy()
    step[:, w // 2 :] += 0.1 * support
    args = dict(units_per_mm=u, jitter=0.0)
    bled = sss.filter(irr, flat, footprint, ids, "preintegrated", m, **args)
    cut = sss.filter(irr, step, footprint, ids, "preintegrated", m, **args)
    left = slice(w // 2 - 3, w // 2)
    assert np.all(bled[:, left] > 0)
    np.testing.assert_array_equal(cut[:, left], 0)
    assert np.all(cut[:, w // 2 :] > 0)


def test_filter_with_a_kernel_object_equals_the_name(gbuffer):
    irr, depth, footprint, ids = inputs_of(gbuffer)
    m = sss.Model("better-dipole", preset="skin1")
    by_name = sss.filter(irr, depth, footprint, ids, "guided", m, units_per_mm=0.05, taps=5, k=1.0)
    by_obj = sss.filter(irr, depth, footprint, ids, sss.kernel(m, "guided", taps=5, k=1.0), units_per_mm=0.05)
    np.testing.assert_array_equal(by_name, by_obj)
    # Strided (non-contiguous) inputs are read in logical order.
    wide = np.zeros(irr.shape[:2] + (6,), np.float32)
    wide[..., ::2] = irr
    strided = sss.filter(wide[..., ::2], depth, footprint, ids, "guided", m, units_per_mm=0.05, taps=5, k=1.0)
    np.testing.assert_array_equal(strided, by_name)


def test_filter_of_a_flat_irradiance_is_the_total_reflectance_in_the_interior():
    # A uniform irradiance on a large flat object at one depth: away from the edges (further
    # than the kernel's widest tap) the exitance is E times the kernel's total weight, the
    # model's R per channel.
    h, w = 64, 64
    m = sss.Model("better-dipole", preset="skin1")
    support = np.abs(sss.kernel(m, "preintegrated").taps[:, 0]).max()
    irr = np.ones((h, w, 3), np.float32)
    depth = np.full((h, w), 10.0, np.float32)
    footprint = np.full((h, w), support / 16, np.float32)  # the widest tap 16 pixels out
    ids = np.zeros((h, w), np.int32)
    out = sss.filter(irr, depth, footprint, ids, "preintegrated", m, jitter=0.0)
    centre = out[24:40, 24:40].reshape(-1, 3)
    np.testing.assert_allclose(centre, np.tile(m.total_diffuse_reflectance, (256, 1)), rtol=2e-3)
