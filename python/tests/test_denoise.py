"""frepray.denoise: Open Image Denoise on a render, guided by its albedo and normal AOVs."""

import numpy as np
import pytest

import frepray
from conftest import ROOT, run_cli



def rmse(a, b):
    """RMSE of what a display shows (values clipped to [0, 1]): the light's own pixels,
    hundreds of times brighter than the rest, would otherwise decide it alone."""
    return float(np.sqrt(np.mean((np.clip(a, 0, 1) - np.clip(b, 0, 1)) ** 2)))


def test_denoising_a_noisy_render_brings_it_closer_to_the_reference(tmp_path):
    scene = frepray.load(ROOT / "scenes/cornell.toml")
    size = dict(width=96, height=72, seed=3)
    noisy = frepray.render(scene, spp=4, aovs=["albedo", "normal"], **size)
    reference = frepray.render(scene, spp=256, **size).image()
    out = tmp_path / "denoised.exr"
    clean = frepray.denoise(noisy, out)
    assert clean.shape == reference.shape and clean.dtype == np.float32
    before, after = rmse(noisy.image(), reference), rmse(clean, reference)
    assert after < 0.6 * before, (before, after)
    # Written to its own file, labelled, with the render's record; the state untouched.
    rgb, _ = frepray.read_exr(out)
    np.testing.assert_array_equal(rgb, clean)
    attrs = frepray.exr_attributes(out)
    assert attrs["frepray.denoised"].startswith("Intel Open Image Denoise")
    assert "albedo + normal" in attrs["frepray.denoised"]
    assert attrs["frepray.settings"] == noisy.attributes()["frepray.settings"]
    assert "frepray.denoised" not in noisy.attributes()
    with pytest.raises(ValueError, match=".exr"):
        frepray.denoise(noisy, tmp_path / "denoised.png")


def test_the_cli_writes_a_labelled_copy_beside_the_unbiased_image(cli, tmp_path):
    import subprocess

    out, copy = tmp_path / "c.exr", tmp_path / "c-denoised.exr"
    args = ["render", ROOT / "scenes/cornell.toml", "--width", "48", "--height", "36",
            "--spp", "4", "--seed", "3", "--aovs", "albedo,normal", "--quiet"]
    run_cli(cli, *args, "-o", out, "--denoised", copy)
    attrs = frepray.exr_attributes(copy)
    assert "albedo + normal" in attrs["frepray.denoised"], attrs
    assert "frepray.denoised" not in frepray.exr_attributes(out)
    # The CLI loads the library pyoidn ships: on the same render, the same result.
    state = frepray.render(frepray.load(ROOT / "scenes/cornell.toml"), spp=4, seed=3,
                           width=48, height=36, aovs=["albedo", "normal"])
    np.testing.assert_array_equal(frepray.read_exr(out)[0], state.image())
    np.testing.assert_allclose(frepray.read_exr(copy)[0], frepray.denoise(state),
                               rtol=1e-3, atol=1e-4)
    # Never over the unbiased image, and nothing written when refused.
    same = subprocess.run([str(cli), *map(str, args), "-o", tmp_path / "x.exr",
                           "--denoised", tmp_path / "x.exr"], cwd=ROOT, capture_output=True,
                          text=True)
    assert same.returncode != 0 and "never replaces the unbiased one" in same.stderr
    assert not (tmp_path / "x.exr").exists()
