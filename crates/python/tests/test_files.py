"""Files and packaging: write_exr and write_png against what `sss render` writes, the text
progress bar, and the distribution's name."""

import importlib.metadata
import subprocess

import numpy as np
import pytest

import sss


def test_pip_install_name_is_the_import_name():
    # `pip install sss` then `import sss`: the distribution that provides the module `sss`
    # is named `sss`, at the module's version.
    assert "sss" in importlib.metadata.packages_distributions().get("sss", []), (
        importlib.metadata.packages_distributions().get("sss")
    )
    assert importlib.metadata.version("sss") == sss.__version__


def test_write_exr_gives_back_what_sss_render_wrote(small_scene, run_sss, sss_bin, tmp_path):
    cli = tmp_path / "cli.exr"
    run_sss("render", small_scene, "--method", "pathtrace", "--spp", 2, "--out", cli)
    read = sss.read_exr(cli)
    alpha = read.pop("alpha")
    # The beauty first, the other layers in EXR's (alphabetical) channel order.
    assert list(read) == ["total", "std_error", "subsurface"], list(read)
    ours = tmp_path / "ours.exr"
    sss.write_exr(ours, read, alpha=alpha, attributes={"sss/method": "pathtrace", "note": "é"})
    again = sss.read_exr(ours)
    assert list(again) == ["alpha", "total", "std_error", "subsurface"], list(again)
    for name, img in read.items():
        np.testing.assert_array_equal(again[name], img, err_msg=name)
    np.testing.assert_array_equal(again["alpha"], alpha)
    # `sss diff` reads it as it reads its own files: identical layers.
    for layer in ["subsurface", "total"]:
        out = subprocess.run([str(sss_bin), "diff", str(ours), str(cli), "--layer", layer],
                             capture_output=True, text=True)
        assert out.returncode == 0, out.stderr
        assert "rmse 0" in out.stdout.replace(":", ""), out.stdout
    # A single image is the part `beauty`, float64 accepted; negatives written as 0.
    img = np.linspace(-1.0, 2.0, 4 * 5 * 3).reshape(4, 5, 3)
    one = tmp_path / "one.exr"
    sss.write_exr(one, img)
    back = sss.read_exr(one)
    assert list(back) == ["beauty"]
    np.testing.assert_allclose(back["beauty"], np.maximum(img, 0.0), rtol=1e-7)


def test_write_exr_refuses_bad_layers_and_leaves_no_file(tmp_path):
    out = tmp_path / "bad.exr"
    a = np.zeros((4, 5, 3), np.float32)
    with pytest.raises(ValueError, match=r"has shape \(4, 6, 3\) but .* has \(4, 5, 3\)"):
        sss.write_exr(out, {"total": a, "other": np.zeros((4, 6, 3), np.float32)})
    with pytest.raises(ValueError, match=r"alpha must have shape \(4, 5\)"):
        sss.write_exr(out, a, alpha=np.zeros((5, 4), np.float32))
    with pytest.raises(TypeError, match="float32"):
        sss.write_exr(out, a.astype(np.int32))
    with pytest.raises(ValueError, match="layer `a.b`"):
        sss.write_exr(out, {"a.b": a})
    with pytest.raises(ValueError, match="at least one image"):
        sss.write_exr(out, {})
    assert list(tmp_path.iterdir()) == []


def test_write_png_matches_sss_render_png(small_scene, run_sss, tmp_path):
    exr, png = tmp_path / "a.exr", tmp_path / "a.png"
    run_sss("render", small_scene, "--out", exr, "--png", png)
    ours = tmp_path / "ours.png"
    sss.write_png(ours, sss.read_exr(exr)["total"])
    assert ours.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # The EXR holds float32 of the render's float64: the 8-bit pixels are the same.
    assert ours.read_bytes() == png.read_bytes()
    dark = tmp_path / "dark.png"
    sss.write_png(dark, sss.read_exr(exr)["total"], exposure=1e-6)
    assert dark.read_bytes() != ours.read_bytes()
    with pytest.raises(ValueError, match="exposure must be"):
        sss.write_png(dark, sss.read_exr(exr)["total"], exposure=0.0)


def test_progress_true_draws_a_text_bar(small_scene, capsys):
    sss.render(small_scene, "pathtrace", spp=2, progress=True)
    err = capsys.readouterr().err
    frames = err.split("\r")
    assert frames[0] == "", err
    last = frames[-1]
    assert last.startswith("pathtrace 100% ") and last.endswith("]\n"), repr(last)
    done, total = last.split()[2].split("/")
    assert done == total and int(total) > 0, last
    assert err.count("\n") == 1, repr(err)
    sss.monte_carlo(preset="skin1", r_max=1.0, bins=4, photons=1000, progress=True)
    assert capsys.readouterr().err.rstrip("\n").split("\r")[-1].startswith("photons 100% 3000/3000")
    sss.render(small_scene, "separable", progress=False)
    assert capsys.readouterr().err == ""
    with pytest.raises(TypeError, match="progress must be True, False, None or a callable"):
        sss.render(small_scene, "separable", progress="yes")
