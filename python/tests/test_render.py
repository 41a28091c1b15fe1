"""Renders: numpy images, exact merges of sample ranges, the CLI's files, Ctrl-C.

What is exact (docs/render-state.md): merging [0, N) and [N, 2N) gives the per-pixel
sample counts of one render of [0, 2N) bit for bit and its sums to ~1e-12 relative
(the additions happen in another order); a merge through bytes equals the merge in
memory bit for bit."""

import json
import os
import signal
import threading
import time
import warnings

import numpy as np
import pytest

import frepray
from conftest import SMALL, run_cli

N = 3


@pytest.mark.parametrize("estimator", ["balance", "optimal-direct"])
def test_split_merges_into_the_whole(many_lights, estimator):
    opts = dict(SMALL, estimator=estimator, seed=11)
    whole = frepray.render(many_lights, samples=(0, 2 * N), **opts)
    first = frepray.render(many_lights, samples=(0, N), **opts)
    second = frepray.render(many_lights, samples=(N, 2 * N), **opts)

    merged = frepray.merge([first, second])
    assert merged.samples == [(0, 2 * N)] == whole.samples
    assert np.array_equal(merged.sample_counts(), whole.sample_counts())
    assert (whole.sample_counts() == 2 * N).all()
    np.testing.assert_allclose(merged.sums(), whole.sums(), rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(merged.image_f64(), whole.image_f64(), rtol=1e-12,
                               atol=1e-12)

    # In place, and through the serialised form: bit for bit the same.
    via_bytes = frepray.RenderState.from_bytes(first.to_bytes())
    via_bytes.merge(frepray.RenderState.from_bytes(second.to_bytes()))
    assert via_bytes.to_bytes() == merged.to_bytes()
    assert np.array_equal(via_bytes.sums(), merged.sums())


def test_image_arrays(many_lights):
    st = frepray.render(many_lights, spp=2, aovs=["depth", "normal"], **SMALL)
    img = st.image()
    assert img.shape == (16, 24, 3) and img.dtype == np.float32
    assert np.isfinite(img).all() and img.max() > 0
    aovs = st.aovs()
    assert set(aovs) == {"depth", "normal.X", "normal.Y", "normal.Z"}
    assert all(a.shape == (16, 24) and a.dtype == np.float32 for a in aovs.values())
    assert np.array_equal(img, st.image_f64()[:, :, :3].astype(np.float32))


def test_numpy_equals_the_cli_exr(many_lights, cli, tmp_path):
    exr = tmp_path / "cli.exr"
    run_cli(cli, "render", many_lights.source()[1], "-o", exr, "--spp", "2",
            "--seed", "7", "--estimator", "optimal-direct", "--width", "24", "--height", "16",
            "--aovs", "depth", "--quiet")
    st = frepray.render(many_lights, spp=2, seed=7, estimator="optimal-direct",
                        aovs=["depth"], **SMALL)
    rgb, aovs = frepray.read_exr(exr)
    img = st.image()
    assert rgb.shape == img.shape and rgb.dtype == img.dtype == np.float32
    assert np.array_equal(rgb, img)
    assert np.array_equal(aovs["depth"], st.aovs()["depth"])
    # And the EXR Python writes is the same file content.
    st.write_exr(tmp_path / "py.exr")
    assert np.array_equal(frepray.read_exr(tmp_path / "py.exr")[0], img)
    # Both record the same settings; the CLI's adds the render's statistics.
    cli_attrs, py_attrs = frepray.exr_attributes(exr), frepray.exr_attributes(tmp_path / "py.exr")
    settings = json.loads(py_attrs["frepray.settings"])
    assert (settings["seed"], settings["estimator"], settings["aovs"]) == (7, "optimal-direct", ["depth"])
    assert cli_attrs["frepray.settings"] == py_attrs["frepray.settings"]
    assert cli_attrs["frepray.samples_rendered"] == str(24 * 16 * 2)
    assert "frepray.statistics" not in py_attrs


@pytest.mark.parametrize("flags", [["--per-light"], ["--pixel-center"],
                                   ["--per-light", "--pixel-center"]])
def test_per_light_and_pixel_center_equal_the_cli(many_lights, cli, tmp_path, flags):
    exr = tmp_path / "cli.exr"
    run_cli(cli, "render", many_lights.source()[1], "-o", exr, "--spp", "2", "--seed", "5",
            "--estimator", "optimal-direct", "--width", "24", "--height", "16", "--quiet", *flags)
    st = frepray.render(many_lights, spp=2, seed=5, estimator="optimal-direct",
                        per_light="--per-light" in flags,
                        pixel_center="--pixel-center" in flags, **SMALL)
    assert np.array_equal(frepray.read_exr(exr)[0], st.image())
    # Each option changes the optimal estimator's image (so the keyword is not ignored).
    plain = frepray.render(many_lights, spp=2, seed=5, estimator="optimal-direct", **SMALL)
    assert not np.array_equal(plain.image(), st.image())


@pytest.mark.parametrize("integrator", ["direct", "path"])
def test_batched_engine_gives_the_same_state(many_lights, cli, tmp_path, integrator):
    opts = dict(SMALL, spp=2, seed=6, estimator="optimal-direct", integrator=integrator)
    per_ray = frepray.render(many_lights, **opts)
    batched = frepray.render(many_lights, engine="batched", **opts)
    assert np.array_equal(per_ray.sums(), batched.sums())
    assert np.array_equal(per_ray.sample_counts(), batched.sample_counts())
    exr = tmp_path / "cli.exr"
    run_cli(cli, "render", many_lights.source()[1], "-o", exr, "--spp", "2", "--seed", "6",
            "--estimator", "optimal-direct", "--integrator", integrator, "--width",
            str(SMALL["width"]), "--height", str(SMALL["height"]), "--quiet",
            "--engine", "batched")
    assert np.array_equal(frepray.read_exr(exr)[0], batched.image())
    with pytest.raises(ValueError, match="per-ray"):
        frepray.render(many_lights, engine="simd", **opts)


def test_python_states_merge_with_the_cli(many_lights, cli, tmp_path):
    opts = dict(SMALL, seed=4)
    a = frepray.render(many_lights, samples=(0, 2), **opts)
    b = frepray.render(many_lights, samples=(2, 4), **opts)
    a.write(tmp_path / "a.state")
    b.write(tmp_path / "b.state")
    run_cli(cli, "merge", tmp_path / "a.state", tmp_path / "b.state",
            "-o", tmp_path / "m.exr", "-o", tmp_path / "m.state")
    merged = frepray.merge([a, b])
    assert frepray.RenderState.read(tmp_path / "m.state").to_bytes() == merged.to_bytes()
    assert np.array_equal(frepray.read_exr(tmp_path / "m.exr")[0], merged.image())


def test_merge_refuses_overlaps_and_other_renders(many_lights):
    a = frepray.render(many_lights, samples=(0, 2), **SMALL)
    with pytest.raises(frepray.RenderError):
        a.merge(frepray.render(many_lights, samples=(1, 3), **SMALL))
    with pytest.raises(frepray.RenderError):
        a.merge(frepray.render(many_lights, samples=(2, 3), seed=99, **SMALL))


def test_same_image_at_any_thread_count(many_lights):
    a = frepray.render(many_lights, spp=2, threads=1, **SMALL)
    b = frepray.render(many_lights, spp=2, threads=2, **SMALL)
    assert np.array_equal(a.sums(), b.sums())


def test_ctrl_c_stops_a_render_with_a_partial_state(many_lights):
    # SIGINT to this process while a long render runs: the render stops within a
    # sample and KeyboardInterrupt carries the partial state. Python's own SIGINT handler
    # is installed for the test: a test run started in the background (`cmd &` in a
    # script) inherits SIGINT ignored, and Python then installs no handler, so the
    # signal was lost and the render ran on for hours. The render is bounded (about a
    # minute at 24 x 16 unstopped), so a lost signal fails the test instead of hanging.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt) as e:
            frepray.render(many_lights, spp=20_000, threads=1, **SMALL)
    finally:
        timer.cancel()
        signal.signal(signal.SIGINT, previous)
    state = e.value.state
    assert state.partial
    assert state.sample_counts().max() < 20_000


def test_render_releases_the_gil(many_lights):
    # While a render runs on another thread, this one keeps running Python.
    done = threading.Event()
    worker = threading.Thread(
        target=lambda: (frepray.render(many_lights, spp=1, threads=1), done.set()))
    ticks = 0
    worker.start()
    while not done.is_set():
        ticks += 1
        time.sleep(0.005)
    worker.join()
    assert ticks > 5


def test_training_options_and_min_depth_equal_the_cli(many_lights, cli, tmp_path):
    trained = ["--techniques", "light-trained:1,light-uniform:1", "--trained-grid", "1",
               "--trained-floor", "0.5", "--trained-spp", "2"]
    deep = ["--integrator", "path", "--min-depth", "2", "--max-depth", "2"]
    kw = dict(techniques="light-trained:1,light-uniform:1", trained_grid=1,
              trained_floor=0.5, trained_spp=2)
    for flags, opts in [(trained, kw), (deep, dict(integrator="path", min_depth=2,
                                                   max_depth=2))]:
        exr = tmp_path / "cli.exr"
        run_cli(cli, "render", many_lights.source()[1], "-o", exr, "--spp", "2", "--seed",
                "5", "--estimator", "optimal-direct", "--width", "24", "--height", "16",
                "--quiet", *flags)
        st = frepray.render(many_lights, spp=2, seed=5, estimator="optimal-direct",
                            **opts, **SMALL)
        assert np.array_equal(frepray.read_exr(exr)[0], st.image())
    # The training options change the image (they are not ignored).
    default = frepray.render(many_lights, spp=2, seed=5, estimator="optimal-direct",
                             techniques=kw["techniques"], **SMALL)
    assert not np.array_equal(default.image(), frepray.render(
        many_lights, spp=2, seed=5, estimator="optimal-direct", **kw, **SMALL).image())
    with pytest.raises(Exception, match="trained_grid"):
        frepray.render(many_lights, spp=1, trained_grid=0, **SMALL)


def test_options_the_render_ignores_are_warned_about(many_lights):
    # The CLI's warnings, from the same library call (frepray::Settings), with the
    # keyword arguments' names.
    opts = dict(SMALL, estimator="balance", spp=1)
    with pytest.warns(UserWarning) as caught:
        frepray.render(many_lights, beta=3.0, ridge=0.5, **opts)
    messages = [str(w.message) for w in caught]
    assert any(m.startswith("beta has no effect here") and "estimator power" in m
               for m in messages), messages
    assert any(m.startswith("ridge has no effect here") for m in messages), messages
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        frepray.render(many_lights, beta=3.0, **dict(opts, estimator="power"))


def test_bench_rows_are_the_clis(many_lights):
    # frepray.bench is `frepray bench`'s measurement (frepray::bench::bench).
    rows = frepray.bench(many_lights, spp=1, **SMALL)
    assert [(r["backend"], r["integrator"]) for r in rows] == [("cpu", "direct"),
                                                              ("cpu", "path")]
    for r in rows:
        assert (r["width"], r["height"], r["spp"]) == (24, 16, 1)
        assert r["msamples_per_s"] > 0 and r["mrays_per_s"] >= r["msamples_per_s"]
        assert r["stages"]["camera rays"] >= 0 and len(r["stages"]) == 5
    with pytest.raises(frepray.RenderError, match="auto"):
        frepray.bench(many_lights, spp=1, backends=["auto"], **SMALL)
    with pytest.raises(ValueError, match="backend"):
        frepray.bench(many_lights, spp=1, backends=["tpu"], **SMALL)


def test_gpu_adapters_are_listed_as_the_cli_lists_them():
    # Each line as `frepray gpu list` prints it: index, name, backend, type, features;
    # configure_gpu reports the adapter chosen (None: the first high-performance one).
    lines = frepray.gpu_adapters()
    for i, line in enumerate(lines):
        assert line.startswith(f"{i}: ") and "f64 " in line and "timestamps " in line, line
    # No keyword: the options in force, unchanged (they are set once per process).
    assert frepray.configure_gpu()["adapter"] is None
