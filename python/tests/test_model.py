"""Bare models: F and its gradient at numpy points, the preview picture."""

import numpy as np
import pytest

import frepray
from conftest import ROOT

TORUS = """
let R = 1.0
let r = 0.35
output r*r - (sqrt(x*x + y*y) - R)^2 - z*z
"""


def torus(p):
    x, y, z = p.T
    return 0.35**2 - (np.sqrt(x * x + y * y) - 1.0) ** 2 - z * z


def test_eval_matches_the_closed_form():
    m = frepray.model(TORUS)
    p = np.random.default_rng(0).uniform(-1.5, 1.5, (500, 3))
    v = m.eval(p)
    assert v.shape == (500,) and v.dtype == np.float64
    np.testing.assert_allclose(v, torus(p), rtol=1e-14, atol=1e-14)


def test_gradient_matches_finite_differences():
    m = frepray.model(TORUS)
    p = np.random.default_rng(1).uniform(-1.5, 1.5, (50, 3)) + 1e-3
    v, g = m.gradient(p)
    assert g.shape == (50, 3)
    np.testing.assert_allclose(v, m.eval(p), rtol=0, atol=0)
    h = 1e-6
    for k in range(3):
        e = np.zeros(3)
        e[k] = h
        fd = (m.eval(p + e) - m.eval(p - e)) / (2 * h)
        np.testing.assert_allclose(g[:, k], fd, rtol=1e-5, atol=1e-6)


def test_model_files_and_sign_convention():
    m = frepray.model(str(ROOT / "models/examples/bumpy_ball.frep"))
    lo, hi = m.bounds
    assert all(a < b for a, b in zip(lo, hi))
    v = m.eval(np.array([[0.0, 0.0, 0.0], [10.0, 10.0, 10.0]]))
    assert v[0] > 0 > v[1]  # F >= 0 inside


def test_bad_models_raise():
    with pytest.raises(frepray.ModelError):
        frepray.model("output sphere(")
    with pytest.raises(ValueError):
        frepray.model(TORUS).eval(np.zeros((3, 2)))


def test_preview():
    m = frepray.model("output sphere([0, 0, 0], 1)")
    st = m.preview(width=24, height=16, spp=2)
    img = st.image()
    assert img.shape == (16, 24, 3) and img.max() > 0
    depth = m.preview(width=24, height=16, spp=1, look="depth").aovs()["depth"]
    assert depth.max() > 0 and depth.min() == 0  # the sphere, and misses around it


def test_mesh_is_closed_on_the_surface_with_the_torus_volume():
    m = frepray.model(TORUS)
    v, t = m.mesh(resolution=48)
    assert v.dtype == np.float64 and t.dtype == np.uint32 and v.shape[1] == t.shape[1] == 3
    np.testing.assert_allclose(m.eval(v), 0.0, atol=1e-9)
    # Closed and consistently oriented: each directed edge once, its reverse once.
    edges = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    directed = set(map(tuple, edges.tolist()))
    assert len(directed) == len(edges)
    assert all((b, a) in directed for a, b in directed)
    a, b, c = (v[t[:, k]] for k in range(3))
    volume = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
    exact = 2 * np.pi**2 * 1.0 * 0.35**2
    assert abs(volume / exact - 1) < 0.03, volume
    with pytest.raises(ValueError, match="resolution"):
        m.mesh(resolution=0)
