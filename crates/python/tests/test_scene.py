"""Scenes as objects (Mitsuba 3's load_dict / load_file): a dict with the scene file's
structure renders exactly as the TOML text does; a scene's description comes back as a dict
to edit; bad descriptions get the scene file's messages, naming the key."""

import numpy as np
import pytest

import sss
from conftest import SMALL_SCENE

#: SMALL_SCENE (conftest) written out as a dict by hand.
SMALL_DICT = {
    "camera": {"position": [0.0, 0.0, 4.0], "target": [0.0, 0.0, 0.0], "up": [0.0, 1.0, 0.0],
               "fov": 30.0, "resolution": [24, 18]},
    "lights": [
        {"type": "directional", "direction": [0.0, 0.0, -1.0], "irradiance": 1.0},
        {"type": "environment", "radiance": [0.05, 0.06, 0.08]},
    ],
    "materials": {
        "skin": {"type": "translucent", "model": "better-dipole", "preset": "skin1",
                 "units_per_mm": 0.1},
        "clay": {"type": "diffuse", "albedo": 0.6},
    },
    "objects": [
        {"material": "skin", "shape": "sphere", "radius": 1.0},
        {"material": "clay", "shape": "sphere", "radius": 0.3,
         "transform": {"translate": [1.3, -0.5, 0.5]}},
    ],
}


def test_a_dict_renders_as_the_scene_file_does(small_scene):
    expected = sss.render(small_scene, "pathtrace", spp=2, seed=3)
    scene = sss.load_dict(SMALL_DICT)
    assert isinstance(scene, sss.Scene)
    assert scene.resolution == (24, 18) and scene.materials == ["skin", "clay"]
    assert len(scene.objects) == 2 and "2 object(s)" in repr(scene)
    for given in (scene, SMALL_DICT):
        out = sss.render(given, "pathtrace", spp=2, seed=3)
        for layer in ("total", "subsurface", "alpha"):
            np.testing.assert_array_equal(out[layer], expected[layer], err_msg=layer)


def test_a_description_comes_back_to_edit(small_scene):
    d = sss.load_file(small_scene).to_dict()
    assert d["materials"]["skin"]["preset"] == "skin1" and len(d["objects"]) == 2
    d["camera"]["resolution"] = [12, 9]
    d["objects"][0]["radius"] = np.float64(0.5)     # numpy scalars and arrays are taken too
    d["lights"][0]["direction"] = np.array([0.0, 0.0, -1.0])
    out = sss.render(sss.load_dict(d), "separable")
    assert out["total"].shape == (9, 12, 3)
    # The edit took: a smaller sphere covers fewer pixels than the unedited one at 12x9.
    small = sss.render(small_scene, "separable", resolution=(12, 9))
    assert 0 < out["coverage"].sum() < small["coverage"].sum()
    # The description is a copy: editing it does not change the scene.
    scene = sss.load_file("sphere")
    scene.to_dict()["camera"]["resolution"] = [1, 1]
    assert scene.resolution == (160, 120)
    assert scene.to_dict()["objects"][0]["shape"] == "sphere"


def test_bad_descriptions_name_the_key():
    d = {**SMALL_DICT, "objects": [{"material": "nope", "shape": "sphere", "radius": 1.0}]}
    with pytest.raises(ValueError) as e:
        sss.load_dict(d)
    assert "objects[0].material" in str(e.value) and "nope" in str(e.value), str(e.value)
    d = {**SMALL_DICT, "objects": [{"material": "skin", "shape": "sphere", "radius": -1.0}]}
    with pytest.raises(ValueError, match="radius"):
        sss.load_dict(d)
    with pytest.raises(TypeError, match=r"scene `camera.fov`: a object has no place"):
        sss.load_dict({**SMALL_DICT, "camera": {**SMALL_DICT["camera"], "fov": object()}})
    d = {**SMALL_DICT, "objects": [{"material": "skin", "shape": "mesh", "file": "nowhere.obj"}]}
    with pytest.raises(ValueError) as e:
        sss.load_dict(d)
    assert "nowhere.obj" in str(e.value) and "mesh_dirs=[...]" in str(e.value), str(e.value)
    with pytest.raises(TypeError, match="scene must be a Scene, a dict"):
        sss.render(3)
