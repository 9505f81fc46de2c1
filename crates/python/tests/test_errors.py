"""Bad input: the right exception, with the message `sss` prints; arrays of the wrong shape
or dtype refused with a message naming the argument."""

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
    assert str(e.value) == expected


def test_monte_carlo_bad_request_has_the_cli_message(sss_error):
    expected = sss_error("profile", "--model", "monte-carlo", "--preset", "skin1", "--r-max", 0, "--steps", 2)
    with pytest.raises(ValueError) as e:
        sss.monte_carlo(preset="skin1", r_max=0.0, bins=2)
    assert str(e.value) == expected


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
    with pytest.raises(ValueError, match="not an option of method exact"):
        sss.render(small_scene, "exact", spp=4)
    expected = sss_error("render", small_scene, "--method", "pathtrace", "--spp", "x")
    with pytest.raises(ValueError) as e:
        sss.render(small_scene, "pathtrace", spp="x")
    assert str(e.value) == expected


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
    with pytest.raises(ValueError) as e:
        sss.kernel(m, taps=0)
    assert str(e.value) == expected
    expected = sss_error("kernel", "--preset", "skin1", "--method", "exact2d")
    with pytest.raises(ValueError) as e:
        sss.kernel(m, "exact2d")
    assert str(e.value) == expected
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
    with pytest.raises(ValueError, match="--jitter must lie in"):
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
        m.rd([1.0, 2.0])


def test_diff_refuses_bad_images():
    a = np.zeros((4, 4, 3), np.float32)
    with pytest.raises(ValueError, match="a is 4x4 but ref is 5x4"):
        sss.diff(a, np.zeros((4, 5, 3), np.float32))
    bad = a.copy()
    bad[1, 1, 1] = np.inf
    with pytest.raises(ValueError, match="non-finite"):
        sss.diff(bad, a)
    with pytest.raises(ValueError, match="eps must be"):
        sss.diff(a, a, eps=0.0)


def test_a_progress_that_is_not_callable_is_refused_before_the_work(small_scene):
    with pytest.raises(TypeError, match=r"progress must be a callable progress\(done, total\), got int"):
        sss.render(small_scene, progress=3)
    with pytest.raises(TypeError, match="progress must be a callable"):
        sss.monte_carlo(preset="skin1", r_max=1.0, progress="x")
