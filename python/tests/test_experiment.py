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
