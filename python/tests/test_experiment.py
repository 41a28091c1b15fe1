"""The estimator comparison from Python."""

import math

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
