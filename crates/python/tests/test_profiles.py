"""Models, presets and Monte Carlo against `sss profile` / `sss presets` and closed forms."""

import io
import time

import numpy as np
import pytest

import sss

MODELS = ["standard-dipole", "better-dipole", "directional-dipole", "pbd", "burley", "mc-table"]


def parse_profile(csv: str):
    """`sss profile` CSV: (total (3,), radii (N,), rd (N, 3), se (N, 3) or None)."""
    lines = csv.splitlines()
    assert lines[0].startswith("# total_diffuse_reflectance=")
    total = np.array([float(x) for x in lines[0].split("=")[1].split(",")])
    table = np.loadtxt(io.StringIO("\n".join(lines[2:])), delimiter=",", ndmin=2)
    se = table[:, 4:7] if table.shape[1] == 7 else None
    return total, table[:, 0], table[:, 1:4], se


@pytest.mark.parametrize("kind", MODELS)
def test_rd_equals_sss_profile_for_a_preset(kind, run_sss):
    total, r, rd, _ = parse_profile(
        run_sss("profile", "--model", kind, "--preset", "skin1", "--r-max", 8, "--steps", 60, "--log")
    )
    m = sss.Model(kind, preset="skin1")
    got = m.rd(r)
    assert got.shape == (60, 3) and got.dtype == np.float64
    # The CSV prints shortest round-trip numbers: the values must be bit-identical.
    np.testing.assert_array_equal(got, rd)
    np.testing.assert_array_equal(m.total_diffuse_reflectance, total)


@pytest.mark.parametrize("kind", ["better-dipole", "pbd", "mc-table"])
def test_rd_equals_sss_profile_for_coefficients(kind, run_sss):
    args = ["--sigma-a", "0.02,0.05,0.1", "--sigma-s", "1.5,1.2,0.9", "--g", "0.3", "--eta", "1.4"]
    total, r, rd, _ = parse_profile(
        run_sss("profile", "--model", kind, *args, "--r-max", 4, "--steps", 25)
    )
    m = sss.Model(kind, sigma_a=[0.02, 0.05, 0.1], sigma_s=(1.5, 1.2, 0.9), g=0.3, eta=1.4)
    np.testing.assert_array_equal(m.rd(r), rd)
    np.testing.assert_array_equal(m.total_diffuse_reflectance, total)
    assert m.g == 0.3 and m.eta == 1.4 and m.preset is None and m.kind == kind


def test_rd_of_a_float_and_of_a_strided_array():
    m = sss.Model("burley", preset="marble")
    r = np.linspace(0.0, 3.0, 40)
    full = m.rd(r)
    assert m.rd(1.5).shape == (3,)
    np.testing.assert_array_equal(m.rd(float(r[7])), full[7])
    # A view with a stride of two elements is read in logical order.
    np.testing.assert_array_equal(m.rd(r[::2]), full[::2])


def test_standard_dipole_total_reflectance_closed_form():
    # Jensen et al. 2001: R_d = (α'/2)(1 + exp(-(4/3) A sqrt(3(1-α')))) exp(-sqrt(3(1-α'))),
    # A = (1 + F_dr)/(1 - F_dr), F_dr = -1.440/η² + 0.710/η + 0.668 + 0.0636 η (their Eq. 5).
    sa, ss, eta = np.array([0.01, 0.02, 0.04]), np.array([1.0, 0.8, 0.6]), 1.3
    a = ss / (sa + ss)
    fdr = -1.440 / eta**2 + 0.710 / eta + 0.668 + 0.0636 * eta
    big_a = (1 + fdr) / (1 - fdr)
    s = np.sqrt(3 * (1 - a))
    expected = a / 2 * (1 + np.exp(-4 / 3 * big_a * s)) * np.exp(-s)
    m = sss.Model("standard-dipole", sigma_a=sa, sigma_s=ss, eta=eta)
    # The model's F_dr is the exact integral, not the fit: agree to the fit's accuracy.
    np.testing.assert_allclose(m.total_diffuse_reflectance, expected, rtol=2e-2)


@pytest.mark.parametrize("kind", ["standard-dipole", "better-dipole", "burley"])
def test_sampling_inverts_its_pdf_and_pdf_is_normalised_rd(kind):
    m = sss.Model(kind, preset="ketchup")
    total = m.total_diffuse_reflectance
    for ch in range(3):
        u = np.array([0.05, 0.3, 0.6, 0.9])
        r = m.sample_r(u, ch)
        assert r.shape == (4,) and np.all(np.diff(r) > 0)
        # pdf_r(r) is 2πr R_d(r) / R_d,total: the density of radii proportional to 2πr R_d.
        grid = np.linspace(0.0, 1.2 * r[-1], 20001)
        pdf = m.pdf_r(grid, ch)
        np.testing.assert_allclose(
            pdf[1:], 2 * np.pi * grid[1:] * m.rd(grid[1:])[:, ch] / total[ch], rtol=2e-3
        )
        # The CDF at each sample is its u (trapezoidal integral of the pdf).
        cdf = np.concatenate([[0.0], np.cumsum((pdf[1:] + pdf[:-1]) / 2 * np.diff(grid))])
        np.testing.assert_allclose(np.interp(r, grid, cdf), u, atol=2e-3)
        assert isinstance(m.sample_r(0.5, ch), float)


def test_presets_equal_sss_presets_csv(run_sss):
    rows = run_sss("presets", "--csv").splitlines()[1:]
    got = sss.presets()
    assert list(got) == [r.split(",")[0] for r in rows]
    for row in rows:
        f = row.split(",")
        p = got[f[0]]
        nums = np.array([float(x) for x in f[1:]])
        np.testing.assert_array_equal(p["sigma_s_reduced"], nums[0:3])
        np.testing.assert_array_equal(p["sigma_a"], nums[3:6])
        assert p["eta"] == nums[6]
        np.testing.assert_array_equal(p["published_rd"], nums[7:10])


def test_monte_carlo_equals_sss_profile(run_sss):
    total, r, rd, se = parse_profile(
        run_sss(
            "profile", "--model", "monte-carlo", "--preset", "skin2", "--r-max", 3,
            "--steps", 30, "--photons", 20000, "--seed", 7,
        )
    )
    seen = []
    r2, rd2, se2 = sss.monte_carlo(
        preset="skin2", r_max=3.0, bins=30, photons=20000, seed=7,
        progress=lambda done, total: seen.append((done, total)),
    )
    np.testing.assert_array_equal(r2, r)
    np.testing.assert_array_equal(rd2, rd)
    np.testing.assert_array_equal(se2, se)
    # The last report is the end: every photon of the three channels.
    assert seen and seen[-1] == (3 * 20000, 3 * 20000)
    assert all(b == 3 * 20000 for _, b in seen)


def test_monte_carlo_agrees_with_the_models_far_from_the_source():
    # The diffusion models are within ~20 % of the random walk at a few mean free paths.
    r, rd, se = sss.monte_carlo(preset="skin1", r_max=4.0, bins=20, photons=200_000, seed=3)
    m = sss.Model("pbd", preset="skin1")
    mid = (r > 1.0) & (r < 3.0)
    ratio = rd[mid] / m.rd(r[mid])
    assert np.all(np.abs(ratio - 1) < 0.25), ratio
    assert np.all(se >= 0) and np.all(np.isfinite(rd))


def test_monte_carlo_stops_when_the_callback_raises():
    class Stop(Exception):
        pass

    calls = []

    def cb(done, total):
        calls.append(done)
        raise Stop("enough")

    t = time.perf_counter()
    with pytest.raises(Stop, match="enough"):
        # Tens of seconds of work if not stopped.
        sss.monte_carlo(preset="skin1", r_max=4.0, bins=20, photons=50_000_000, progress=cb)
    assert time.perf_counter() - t < 5.0
    assert len(calls) == 1
