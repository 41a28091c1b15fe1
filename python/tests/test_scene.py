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
