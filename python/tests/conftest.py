"""Shared fixtures: the repository's paths, a small scene, the CLI binary."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenes"

#: Small and quick: the paper's many-lights scene at 24 x 16.
SMALL = {"width": 24, "height": 16}


def small_dict(**render):
    """A tiny scene as a dict: a lit sphere over a floor."""
    return {
        "camera": {"eye": [0, -4, 1], "target": [0, 0, 0], "resolution": [24, 16]},
        "render": {"integrator": "direct", "estimator": "balance", "spp": 4, **render},
        "materials": {"white": {"type": "diffuse", "reflectance": 0.8}},
        "objects": [{"solid": "sphere([0, 0, 0], 1)", "material": "white"}],
        "lights": [{"type": "sphere", "center": [0, -2, 3], "radius": 0.5, "power": 100}],
    }


@pytest.fixture(scope="session")
def cli() -> Path:
    """The `frepray` binary: the newest built one (scripts/test.sh builds it), else
    built here."""
    found = [p for p in (ROOT / "target/release/frepray", ROOT / "target/debug/frepray")
             if p.exists()]
    if not found:
        subprocess.run(["cargo", "build", "-q", "-p", "frepray-cli"], cwd=ROOT, check=True)
        found = [ROOT / "target/debug/frepray"]
    return max(found, key=lambda p: p.stat().st_mtime)


@pytest.fixture(scope="session")
def many_lights():
    import frepray

    return frepray.load(SCENES / "many-lights.toml")


def run_cli(cli: Path, *args) -> None:
    subprocess.run([os.fspath(cli), *map(os.fspath, args)], check=True, cwd=ROOT,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
