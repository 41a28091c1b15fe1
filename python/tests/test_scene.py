"""Scenes from files and dicts; typed errors with their location."""

import json

import numpy as np
import pytest

import frepray
from conftest import SCENES, small_dict


def test_file_and_dict_give_the_same_image():
    from_file = frepray.load(SCENES / "table.json")
    with open(SCENES / "table.json") as f:
        from_dict = frepray.load_dict(json.load(f), base_dir=SCENES)
    assert from_file.hash == from_dict.hash
    opts = dict(spp=2, width=32, height=24, seed=5)
    a = frepray.render(from_file, **opts)
    b = frepray.render(from_dict, **opts)
    assert np.array_equal(a.sums(), b.sums())
    assert np.array_equal(a.image(), b.image())
    assert a.image().max() > 0


def test_toml_and_json_files_of_one_scene_agree():
    a = frepray.render(frepray.load(SCENES / "table.toml"), spp=1, width=16, height=12)
    b = frepray.render(frepray.load(SCENES / "table.json"), spp=1, width=16, height=12)
    assert np.array_equal(a.image(), b.image())


def test_dict_accepts_numpy_values():
    d = small_dict()
    d["camera"]["eye"] = np.array([0.0, -4.0, 1.0])
    d["render"]["spp"] = np.int64(2)
    s = frepray.load_dict(d)
    assert s.resolution == (24, 16)
    assert s.settings["spp"] == 2


def test_invalid_dict_raises_with_the_key_path():
    d = small_dict()
    d["objects"][0]["material"] = "missing"
    with pytest.raises(frepray.SceneError) as e:
        frepray.load_dict(d)
    assert e.value.key == "objects[0].material"
    assert "missing" in str(e.value)
    assert isinstance(e.value, frepray.Error)

    d = small_dict()
    d["camera"]["resolution"] = [24, "sixteen"]
    with pytest.raises(frepray.SceneError) as e:
        frepray.load_dict(d)
    assert e.value.key.startswith("camera.resolution")


def test_invalid_file_raises_with_line_and_column(tmp_path):
    bad = tmp_path / "bad.toml"
    text = (SCENES / "many-lights.toml").read_text()
    bad.write_text(text.replace('estimator = "balance"', 'estimator = "nonsense"', 1))
    with pytest.raises(frepray.SceneError) as e:
        frepray.load(bad)
    assert e.value.file.endswith("bad.toml")
    assert e.value.line == 17 and e.value.column > 0
    assert e.value.key == "render.estimator"


def test_render_option_errors_are_typed():
    s = frepray.load_dict(small_dict())
    with pytest.raises(frepray.SceneError) as e:
        frepray.render(s, estimator="nonsense")
    assert e.value.key == "render.estimator"
    with pytest.raises(ValueError):
        frepray.render(s, backend="tpu")
    with pytest.raises(ValueError):
        frepray.render(s, samples=(4, 2))


def test_scene_pickles_as_its_source():
    import pickle

    s = frepray.load_dict(small_dict())
    t = pickle.loads(pickle.dumps(s))
    assert t.hash == s.hash
    f = frepray.load(SCENES / "many-lights.toml")
    assert pickle.loads(pickle.dumps(f)).hash == f.hash


def test_a_number_json_cannot_hold_is_named_by_its_key_path():
    # Was: the position in the JSON text Python made ("line 1 column 24"), not the key.
    d = small_dict()
    d["materials"]["white"]["reflectance"] = float("nan")
    with pytest.raises(frepray.SceneError) as e:
        frepray.load_dict(d)
    assert e.value.key == "materials.white.reflectance"
    assert str(e.value) == "materials.white.reflectance: expected a finite number, found nan"
    assert e.value.line == 0 and e.value.column == 0
    d = small_dict()
    d["objects"][0]["transform"] = {"translate": np.array([0.0, -np.inf, 0.0])}
    with pytest.raises(frepray.SceneError) as e:
        frepray.load_dict(d)
    assert e.value.key == "objects[0].transform.translate[1]"


@pytest.mark.parametrize("kw", [dict(spp=-1), dict(seed=-1), dict(samples=(-1, 2)),
                                dict(threads=-1), dict(width=-16), dict(max_depth=-1),
                                dict(trained_spp=-1), dict(techniques={"light": -1}),
                                dict(techniques=[("bsdf", -1)])], ids=str)
def test_negative_integers_are_value_errors_naming_the_argument(kw):
    # Was: OverflowError ("can't convert negative int to unsigned"), naming nothing.
    s = frepray.load_dict(small_dict())
    (name,) = kw
    with pytest.raises(ValueError, match=f"^{name}: expected a non-negative integer"):
        frepray.render(s, **kw)


def test_negative_integers_elsewhere(tmp_path):
    s = frepray.load_dict(small_dict())
    with pytest.raises(ValueError, match="^spp: expected a non-negative"):
        frepray.experiment(s, ["balance"], [1, -2], out=tmp_path)
    with pytest.raises(ValueError, match="^repeats: expected a non-negative"):
        frepray.experiment(s, ["balance"], [1], repeats=-1, out=tmp_path)
    m = frepray.model("output sphere([0, 0, 0], 1)")
    with pytest.raises(ValueError, match="^width: expected a non-negative"):
        m.preview(width=-1)
    with pytest.raises(ValueError, match="^spp: 4294967296 is too large"):
        frepray.render(s, spp=2**32)


def test_a_dict_scene_with_a_medium_and_an_emitting_object():
    # Beer's law from Python: an absorbing ball (interface boundary) in a dome of
    # radiance 1; the centre pixel sees exp(-2 sigma_a) through the ball's diameter.
    d = {
        "camera": {"eye": [0, -4, 0], "target": [0, 0, 0], "fov": 10, "resolution": [9, 9]},
        "render": {"integrator": "path", "estimator": "optimal-direct",
                   "techniques": [{"technique": "bsdf", "samples": 1},
                                  {"technique": "environment", "samples": 1}]},
        "materials": {"none": {"type": "interface"}},
        "media": {"ink": {"sigma_a": [0.5, 0.25, 1.0], "sigma_s": 0}},
        "objects": [{"solid": "sphere([0, 0, 0], 1)", "material": "none", "medium": "ink"}],
        "environment": {"radiance": 1},
    }
    img = frepray.render(frepray.load_dict(d), spp=4, seed=1).image()
    centre = img[4, 4]
    assert np.allclose(centre, np.exp([-1.0, -0.5, -2.0]), rtol=2e-3), centre
    # An emitting ball seen by the camera shows its emission.
    lamp = {
        "camera": {"eye": [0, -4, 0], "target": [0, 0, 0], "fov": 10, "resolution": [9, 9]},
        "materials": {"lamp": {"type": "diffuse", "reflectance": 0, "emission": [3, 2, 1]}},
        "objects": [{"solid": "sphere([0, 0, 0], 1)", "material": "lamp"}],
    }
    img = frepray.render(frepray.load_dict(lamp), spp=2, seed=1).image()
    assert np.allclose(img[4, 4], [3, 2, 1]), img[4, 4]
    d["media"]["ink"]["g"] = 1.5
    with pytest.raises(frepray.SceneError) as e:
        frepray.load_dict(d)
    assert e.value.key == "media.ink.g"
