"""The GPU back end from Python: `backend="gpu"` renders what `--backend gpu` renders
(wgpu; Mesa's lavapipe on machines without a GPU) into the same RenderState, so a GPU
range merges with a CPU one; a scene it does not cover is refused by name, and
`backend="auto"` renders that one on the CPU with a warning saying why.

Where no adapter exists the tests skip, unless FREPRAY_REQUIRE_GPU=1 (set by
scripts/test.sh), where they fail (GPU.md §11.1)."""

import os

import numpy as np
import pytest

import frepray
from conftest import small_dict


def gpu_render(scene, **kw):
    """A render on the GPU, or a skip where there is no adapter (outside CI)."""
    try:
        return frepray.render(scene, backend="gpu", **kw)
    except frepray.RenderError as e:
        if "no GPU adapter" in str(e) and os.environ.get("FREPRAY_REQUIRE_GPU") != "1":
            pytest.skip(str(e))
        raise


def test_gpu_render_agrees_and_merges_with_the_cpu():
    # Same seed: the GPU follows the CPU's random numbers in f32 (docs/gpu.md), so the
    # images agree pixel for pixel up to rounding, not just in distribution.
    s = frepray.load_dict(small_dict())
    g = gpu_render(s, spp=16, seed=3)
    c = frepray.render(s, spp=16, seed=3)
    assert g.samples == c.samples == [(0, 16)]
    assert np.array_equal(g.sample_counts(), c.sample_counts())
    gi, ci = g.image_f64()[:, :, :3], c.image_f64()[:, :, :3]
    assert ci.max() > 0
    np.testing.assert_allclose(gi.mean(axis=(0, 1)), ci.mean(axis=(0, 1)), rtol=1e-3)
    far = np.abs(gi - ci).sum(axis=2) > 1e-2 * np.maximum(ci.sum(axis=2), 1e-3)
    assert far.mean() < 0.01, f"{far.sum()} pixels differ by more than 1 %"
    # A GPU range and a CPU range merge into [0, 16), equal to the CPU's whole render
    # in distribution (here, with the same seed, up to rounding).
    first = gpu_render(s, samples=(0, 8), seed=3)
    second = frepray.render(s, samples=(8, 16), seed=3)
    merged = frepray.merge([first, second])
    assert merged.samples == [(0, 16)]
    np.testing.assert_allclose(merged.image_f64()[:, :, :3].mean(axis=(0, 1)),
                               ci.mean(axis=(0, 1)), rtol=1e-3)


def test_uncovered_scenes_are_refused_by_name_and_auto_falls_back():
    d = small_dict()
    # A power beyond the 255 the GPU's tapes unroll, so the GPU refuses it.
    d["objects"][0]["solid"] = "sphere([0, 0, 0], 1) - 0.05 * (0.5 * x)^300"
    s = frepray.load_dict(d)
    with pytest.raises(frepray.RenderError, match="PowI|no GPU adapter"):
        frepray.render(s, backend="gpu", spp=1)
    with pytest.warns(UserWarning, match="renders on the CPU"):
        auto = frepray.render(s, backend="auto", spp=2, seed=5)
    cpu = frepray.render(s, spp=2, seed=5)
    assert np.array_equal(auto.sums(), cpu.sums())


def test_gpu_available_says_whether_the_gpu_renders():
    # Was the constant False, while backend="gpu" rendered. An uncovered scene is refused
    # after the adapter is found, so its message says which is the case, at no cost.
    d = small_dict()
    d["objects"][0]["solid"] = "sphere([0, 0, 0], 1) - 0.05 * (0.5 * x)^300"
    with pytest.raises(frepray.RenderError) as e:
        frepray.render(frepray.load_dict(d), backend="gpu", spp=1)
    adapter = "no GPU adapter" not in str(e.value)
    assert frepray.gpu_available() is adapter
    assert bool(frepray.gpu_available) is adapter
    if os.environ.get("FREPRAY_REQUIRE_GPU") == "1":
        assert frepray.gpu_available()


def test_import_gives_mesa_a_private_runtime_directory(tmp_path):
    # Without XDG_RUNTIME_DIR, importing frepray makes $TMPDIR/frepray-runtime-UID (0700)
    # and points the variable there, so Mesa prints no warning when a device opens.
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k != "XDG_RUNTIME_DIR"}
    env["TMPDIR"] = str(tmp_path)
    code = ("import os, frepray; d = os.environ['XDG_RUNTIME_DIR']; "
            "print(d, oct(os.stat(d).st_mode & 0o777)); frepray.gpu_adapters()")
    r = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    d, mode = r.stdout.split()
    assert (d, mode) == (str(tmp_path / f"frepray-runtime-{os.getuid()}"), "0o700")
    assert "XDG_RUNTIME_DIR" not in r.stderr, r.stderr
