"""Bad input: the right exception, with the message `sss` prints; arrays of the wrong shape
or dtype refused with a message naming the argument."""

import subprocess

import numpy as np
import pytest

import sss


def test_unknown_preset_has_the_cli_message(sss_error):
    expected = sss_error("profile", "--model", "pbd", "--preset", "nope", "--r-max", 1, "--steps", 2)
    with pytest.raises(ValueError) as e:
        sss.Model("pbd", preset="nope")
    assert str(e.value) == expected


def test_invalid_medium_has_the_cli_message(sss_error):
    expected = sss_error(
        "profile", "--model", "better-dipole", "--sigma-a", "-1,0,0", "--sigma-s", "1,1,1",
        "--r-max", 1, "--steps", 2,
    )
    with pytest.raises(ValueError) as e:
        sss.Model("better-dipole", sigma_a=[-1, 0, 0], sigma_s=[1, 1, 1])
    assert str(e.value) == expected
    expected = sss_error("profile", "--model", "pbd", "--preset", "skin1", "--eta", -2, "--r-max", 1, "--steps", 2)
    with pytest.raises(ValueError) as e:
        sss.Model("pbd", preset="skin1", eta=-2.0)
    assert str(e.value) == expected


def test_mc_table_eta_range_has_the_cli_message(sss_error):
    expected = sss_error("profile", "--model", "mc-table", "--preset", "skin1", "--eta", 2.0, "--r-max", 1, "--steps", 2)
    with pytest.raises(ValueError) as e:
        sss.Model("mc-table", preset="skin1", eta=2.0)
    # In Python's terms: the keyword `eta` where `sss` says `--eta`.
    assert expected.startswith("--eta 2 is outside"), expected
    assert str(e.value) == expected[len("--"):]


def test_monte_carlo_bad_request_has_the_cli_message(sss_error):
    expected = sss_error("profile", "--model", "monte-carlo", "--preset", "skin1", "--r-max", 0, "--steps", 2)
    with pytest.raises(ValueError) as e:
        sss.monte_carlo(preset="skin1", r_max=0.0, bins=2)
    assert expected.startswith("--r-max 0 must be"), expected
    assert str(e.value) == "r_max" + expected[len("--r-max"):]


def test_unknown_model_and_medium_arguments():
    with pytest.raises(ValueError, match="nope"):
        sss.Model("nope", preset="skin1")
    with pytest.raises(ValueError, match="preset=NAME or both sigma_a"):
        sss.Model("pbd")
    with pytest.raises(ValueError, match="preset=NAME or both sigma_a"):
        sss.Model("pbd", preset="skin1", sigma_a=[1, 1, 1])
    with pytest.raises(ValueError, match="sigma_a must hold three numbers"):
        sss.Model("pbd", sigma_a=[1, 1], sigma_s=[1, 1, 1])
    with pytest.raises(ValueError, match="g applies to sigma_a"):
        sss.Model("pbd", preset="skin1", g=0.5)


def test_missing_scene_file_is_an_os_error_with_the_cli_message(sss_error, tmp_path):
    missing = tmp_path / "missing.toml"
    expected = sss_error("render", missing)
    with pytest.raises(OSError) as e:
        sss.render(missing)
    assert str(e.value) == expected


def test_missing_mesh_says_how_to_add_a_directory_in_python_terms(small_scene, tmp_path):
    text = small_scene.read_text().replace('shape = "sphere"\nradius = 0.3', 'shape = "mesh"\nfile = "nowhere.obj"')
    assert "nowhere.obj" in text
    scene = tmp_path / "mesh.toml"
    scene.write_text(text)
    for given in (scene, text):
        with pytest.raises(ValueError) as e:
            sss.render(given, mesh_dirs=[tmp_path])
        msg = str(e.value)
        assert "nowhere.obj" in msg and "mesh_dirs=[...]" in msg, msg
        assert "--mesh-dir" not in msg and "LoadOptions" not in msg, msg


def test_unknown_scene_name_lists_the_built_in_scenes():
    with pytest.raises(OSError) as e:
        sss.render("bunnyy")
    assert "bunnyy" in str(e.value) and "sphere, toad" in str(e.value), str(e.value)


def test_bad_scene_text_and_method_are_value_errors_with_the_cli_message(sss_error, small_scene, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text(small_scene.read_text().replace("radius = 1.0", "radius = -1.0"))
    expected = sss_error("render", bad)
    with pytest.raises(ValueError) as e:
        sss.render(bad)
    assert str(e.value) == expected
    # `sss` refuses an unknown method while parsing its arguments (clap); the library names
    # the method and every registered one.
    with pytest.raises(ValueError) as e:
        sss.render(small_scene, "nope")
    assert "`nope`" in str(e.value) and all(m in str(e.value) for m in sss.METHODS)
    # The message `sss` prints, in Python's terms: the keyword `spp` where it says `--spp`.
    expected = sss_error("render", small_scene, "--method", "pathtrace", "--spp", "x")
    assert expected.startswith("--spp: invalid value `x`"), expected
    with pytest.raises(ValueError) as e:
        sss.render(small_scene, "pathtrace", spp="x")
    assert str(e.value) == "spp" + expected[len("--spp"):]


def test_options_of_another_method_are_ignored_with_a_warning_as_the_cli_does(small_scene, sss_bin, tmp_path):
    # `sss render --spp 4` with exact warns and renders; so does Python, with a UserWarning.
    exr = tmp_path / "exact.exr"
    cli = subprocess.run([str(sss_bin), "render", str(small_scene), "--spp", "4", "--out", str(exr)],
                         capture_output=True, text=True)
    assert cli.returncode == 0 and "--spp is not an option of method exact; ignored" in cli.stderr, cli.stderr
    with pytest.warns(UserWarning, match=r"^spp is not an option of method exact; ignored$"):
        out = sss.render(small_scene, "exact", spp=4)
    np.testing.assert_array_equal(out["total"], sss.read_exr(exr)["total"])
    assert out["warnings"][0] == "spp is not an option of method exact; ignored"
    # An option of no method is a misspelling: a TypeError, as for any unknown keyword,
    # naming what the method does take.
    with pytest.raises(TypeError) as e:
        sss.render(small_scene, "pathtrace", sp=4)
    msg = str(e.value)
    assert "'sp'" in msg and "spp" in msg and "probe_energy" in msg and "--" not in msg, msg


def test_method_messages_name_keywords_not_flags(small_scene):
    # Every option's message in the caller's terms: the keyword (underscored), and a listed
    # value as the keyword argument that selects it.
    cases = [
        ("pathtrace", {"spp": 0}, "spp must be at least 1"),
        ("pathtrace", {"probe_energy": 2.0}, "probe_energy must lie strictly between 0 and 1"),
        ("dual-tree-fmm", {"expansion_order": 3}, "expansion_order must be 1 or 2"),
        ("manylight", {"max_splits": 0}, "max_splits must be in 1..=2^30"),
        ("separable", {"taps": 5000}, "taps must lie in 1..=1025"),
    ]
    for method, opts, text in cases:
        with pytest.raises(ValueError) as e:
            sss.render(small_scene, method, **opts)
        assert text in str(e.value) and "--" not in str(e.value), (method, str(e.value))
    # The sphere's point light cannot be reached through a dielectric boundary: the message
    # names the keyword argument that lights it.
    with pytest.raises(ValueError) as e:
        sss.render(small_scene, "volpath")
    msg = str(e.value)
    assert 'use boundary="lambertian"' in msg and "--" not in msg, msg


def test_exr_errors(tmp_path, sss_error, small_scene, run_sss):
    with pytest.raises(OSError, match="No such file"):
        sss.read_exr(tmp_path / "missing.exr")
    notexr = tmp_path / "x.exr"
    notexr.write_text("not an exr")
    with pytest.raises(OSError):
        sss.read_exr(notexr)
    a = tmp_path / "a.exr"
    run_sss("render", small_scene, "--out", a)
    # The message `sss` prints, in Python's terms: `layer=` where it says `--layer`.
    expected = sss_error("diff", a, a, "--layer", "nope")
    assert "choose with --layer" in expected
    with pytest.raises(ValueError) as e:
        sss.diff(a, a, layer="nope")
    assert str(e.value) == expected.replace("--layer", "layer=")
    with pytest.raises(ValueError, match="choose with reference_layer="):
        sss.diff(a, a, reference_layer="nope")


def test_kernel_and_filter_arguments(sss_error):
    m = sss.Model("better-dipole", preset="skin1")
    expected = sss_error("kernel", "--preset", "skin1", "--taps", 0)
    assert expected == "--taps must lie in 1..=1025, got 0", expected
    with pytest.raises(ValueError) as e:
        sss.kernel(m, taps=0)
    assert str(e.value) == "taps must lie in 1..=1025, got 0"
    expected = sss_error("kernel", "--preset", "skin1", "--method", "exact2d")
    with pytest.raises(ValueError) as e:
        sss.kernel(m, "exact2d")
    assert str(e.value) == expected.replace("--method", "method")
    with pytest.raises(ValueError, match="unknown kernel `nope`"):
        sss.kernel(m, "nope")
    with pytest.raises(ValueError, match="unknown format"):
        sss.kernel(m).export("pdf")


def shapes(h=8, w=10):
    return (
        np.zeros((h, w, 3), np.float32),
        np.ones((h, w), np.float32),
        np.full((h, w), 0.1, np.float32),
        np.zeros((h, w), np.int32),
    )


def test_filter_refuses_wrong_dtypes_and_shapes():
    m = sss.Model("better-dipole", preset="skin1")
    irr, depth, fp, ids = shapes()
    assert sss.filter(irr, depth, fp, ids, "preintegrated", m).shape == (8, 10, 3)
    with pytest.raises(TypeError, match=r"irradiance must have dtype float32, got float64"):
        sss.filter(irr.astype(np.float64), depth, fp, ids, "preintegrated", m)
    with pytest.raises(ValueError, match=r"irradiance must have shape \(H, W, 3\), got \(8, 10\)"):
        sss.filter(depth, depth, fp, ids, "preintegrated", m)
    with pytest.raises(ValueError, match=r"depth must have shape \(8, 10\), got \(10, 8\)"):
        sss.filter(irr, depth.T.copy(), fp, ids, "preintegrated", m)
    with pytest.raises(TypeError, match=r"object_id must have dtype int32, got int64"):
        sss.filter(irr, depth, fp, ids.astype(np.int64), "preintegrated", m)
    with pytest.raises(TypeError, match=r"footprint must be a numpy array of dtype float32"):
        sss.filter(irr, depth, fp.tolist(), ids, "preintegrated", m)
    with pytest.raises(ValueError, match="needs model="):
        sss.filter(irr, depth, fp, ids, "preintegrated")
    with pytest.raises(ValueError, match="units_per_mm must be positive"):
        sss.filter(irr, depth, fp, ids, "preintegrated", m, units_per_mm=0.0)
    with pytest.raises(ValueError, match="^jitter must lie in"):
        sss.filter(irr, depth, fp, ids, "preintegrated", m, jitter=2.0)


def test_profile_arrays_refused_with_clear_messages():
    m = sss.Model("pbd", preset="skin1")
    with pytest.raises(TypeError, match=r"r must have dtype float64, got int64"):
        m.rd(np.arange(3))
    with pytest.raises(ValueError, match=r"r must have shape \(N,\), got \(2, 2\)"):
        m.rd(np.ones((2, 2)))
    with pytest.raises(ValueError, match=r"r\[1\] is NaN"):
        m.rd(np.array([1.0, np.nan]))
    with pytest.raises(ValueError, match=r"r is -1; it must be a finite number in \[0, inf\)"):
        m.rd(-1.0)
    with pytest.raises(ValueError, match=r"u is 1; it must be a finite number in \[0, 1\)"):
        m.sample_r(1.0, 0)
    with pytest.raises(ValueError, match="channel must be 0, 1 or 2"):
        m.pdf_r(1.0, 3)
    with pytest.raises(TypeError, match="r must be a numpy array"):
        m.rd("1.0")


def test_profiles_take_lists_and_coefficients_take_one_number_as_a_scene_file_does():
    m = sss.Model("pbd", preset="skin1")
    np.testing.assert_array_equal(m.rd([0.5, 1.0]), m.rd(np.array([0.5, 1.0])))
    np.testing.assert_array_equal(m.rd((0.5, 1.0)), m.rd(np.array([0.5, 1.0])))
    np.testing.assert_array_equal(m.sample_r([0.25, 0.5], 1), m.sample_r(np.array([0.25, 0.5]), 1))
    assert m.rd([0.5, 1.0]).shape == (2, 3)
    # sigma_s = 1.0 is [1, 1, 1], as `sigma_s = 1.0` in a scene file.
    scalar = sss.Model("better-dipole", sigma_a=0.01, sigma_s=1.0)
    triple = sss.Model("better-dipole", sigma_a=[0.01] * 3, sigma_s=[1.0] * 3)
    np.testing.assert_array_equal(scalar.sigma_s, [1.0, 1.0, 1.0])
    np.testing.assert_array_equal(scalar.rd(1.0), triple.rd(1.0))
    with pytest.raises(TypeError, match="sigma_s must be a number or a sequence of three"):
        sss.Model("better-dipole", sigma_a=0.01, sigma_s="x")


def test_diff_refuses_bad_images():
    a = np.zeros((4, 4, 3), np.float32)
    # Shapes as numpy gives them: (H, W, 3).
    with pytest.raises(ValueError, match=r"a has shape \(4, 4, 3\) but ref has shape \(4, 5, 3\)"):
        sss.diff(a, np.zeros((4, 5, 3), np.float32))
    bad = a.copy()
    bad[1, 1, 1] = np.inf
    with pytest.raises(ValueError, match="non-finite"):
        sss.diff(bad, a)
    with pytest.raises(ValueError, match="eps must be"):
        sss.diff(a, a, eps=0.0)


def test_a_progress_that_is_not_callable_is_refused_before_the_work(small_scene):
    with pytest.raises(TypeError, match=r"progress must be True, False, None or a callable progress\(done, total\), got int"):
        sss.render(small_scene, progress=3)
    with pytest.raises(TypeError, match="or a callable"):
        sss.monte_carlo(preset="skin1", r_max=1.0, progress="x")
