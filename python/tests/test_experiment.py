"""The estimator comparison from Python."""

import math

import pytest

import frepray


def test_experiment_table(many_lights, tmp_path):
    rows = frepray.experiment(
        many_lights, ["balance", "optimal-direct"], [1, 2], out=tmp_path / "exp",
        reference_spp=8, width=24, height=16, pandas=False)
    assert sorted((r["estimator"], r["spp"]) for r in rows) == [
        ("balance", 1), ("balance", 2), ("optimal-direct", 1), ("optimal-direct", 2)]
    for r in rows:
        assert r["rmse"] > 0 and math.isclose(r["rmse"], math.sqrt(r["mse"]))
        assert r["time_s"] >= 0
        assert {"relmse", "improvement", "speed_up", "overhead"} <= set(r)
    assert all(r["improvement"] == 1.0 for r in rows if r["estimator"] == "balance")
    assert (tmp_path / "exp" / "summary.md").exists()


def test_experiment_at_equal_time(many_lights, tmp_path):
    # Each estimator gets the spp its calibrated cost fits in the budget; one point each.
    rows = frepray.experiment(
        many_lights, ["balance", "optimal-direct", "power@light-bvh+bsdf"], [],
        out=tmp_path / "exp", budget=0.2, reference_spp=16, width=24, height=16, repeats=2,
        pandas=False)
    assert sorted(r["estimator"] for r in rows) == [
        "balance", "optimal-direct", "power@light-bvh:1+bsdf:1"]
    assert all(r["spp"] >= 1 and r["cpu_s"] > 0 for r in rows)
    assert "At equal time" in (tmp_path / "exp" / "summary.md").read_text()


def test_experiment_per_light_pixel_center_and_decompose(many_lights, tmp_path):
    opts = dict(reference_spp=8, width=24, height=16, repeats=2, pandas=False)
    plain = frepray.experiment(many_lights, ["optimal-direct"], [2], out=tmp_path / "a",
                               **opts)
    rows = frepray.experiment(many_lights, ["optimal-direct"], [2], out=tmp_path / "b",
                              per_light=True, decompose=True, **opts)
    by = {(r["estimator"], r["spp"]): r for r in rows}
    # Per-light mode changes the optimal estimator's images (so its MSE), not balance's.
    key = ("optimal-direct", 2)
    assert by[key]["mse"] != {(r["estimator"], r["spp"]): r for r in plain}[key]["mse"]
    for r in rows:
        assert 0.0 <= r["direction_share"] <= 1.0
        assert 0.0 < r["variance_centered"] <= r["variance_jittered"] * 1.5
    centred = frepray.experiment(many_lights, ["balance"], [2], out=tmp_path / "c",
                                 pixel_center=True, **opts)
    assert centred[0]["mse"] != [r for r in plain if r["estimator"] == "balance"][0]["mse"]


def test_experiment_takes_the_render_options(many_lights, tmp_path):
    # The CLI's render flags reach every render of the sweep: depth 2 alone of `path`
    # is a different image from the whole path, a rerun with the same options reuses
    # the renders (the same MSE), and one thread gives the same image as all of them.
    opts = dict(reference_spp=8, width=24, height=16, repeats=1, pandas=False,
                integrator="path", max_depth=2)
    full = frepray.experiment(many_lights, ["power"], [2], out=tmp_path / "a", **opts)
    depth2 = frepray.experiment(many_lights, ["power"], [2], out=tmp_path / "b",
                                min_depth=2, hide_emitters=True, beta=3.0, **opts)
    again = frepray.experiment(many_lights, ["power"], [2], out=tmp_path / "b",
                               min_depth=2, hide_emitters=True, beta=3.0, threads=1, **opts)
    mse = lambda rows: {(r["estimator"], r["spp"]): r["mse"] for r in rows}
    assert mse(full) != mse(depth2)
    assert mse(depth2) == mse(again)
    settings = (tmp_path / "b" / "summary.md").read_text()
    assert "min-depth 2" in settings and "hide_emitters true" in settings
    assert "max_depth 2" in settings and "beta: 3.0" in settings
    with pytest.raises(frepray.SceneError) as e:
        frepray.experiment(many_lights, ["power"], [2], out=tmp_path / "c",
                           trained_floor=2.0, **opts)
    assert e.value.key == "render.trained_floor"


def test_summarize_equals_the_hand_computed_ratios():
    renders = [dict(estimator=e, spp=4, seed=s, time_s=t, mse=v, relmse=v, trimmed_mse=v)
               for e, s, t, v in [("balance", 0, 1.0, 4.0), ("balance", 1, 1.0, 6.0),
                                  ("optimal_direct", 0, 2.0, 1.0),
                                  ("optimal-direct", 1, 2.0, 1.5)]]
    rows = frepray.summarize(renders, "balance")
    opt = next(r for r in rows if r["estimator"] == "optimal-direct")
    assert opt["improvement"] == pytest.approx(2.0)   # √(5 / 1.25)
    assert opt["overhead"] == pytest.approx(1.0)      # 2 s against 1 s
    assert opt["speed_up"] == pytest.approx(2.0)      # 5·1 / (1.25·2)
    assert opt["improvement_ci"][0] <= 2.0 <= opt["improvement_ci"][1]
    with pytest.raises(ValueError, match="estimator"):
        frepray.summarize([dict(spp=1, seed=0, time_s=1, mse=1, relmse=1)])
