"""The mis estimators over numpy arrays."""

import numpy as np
import pytest

from frepray import mis


def draws(n, seed=1):
    rng = np.random.default_rng(seed)
    u = rng.random((n, 2))
    x0, x1 = u[:, 0], np.sqrt(u[:, 1])  # uniform; pdf 2x
    pdfs = lambda x: np.stack([np.ones_like(x), 2 * x], axis=-1)  # noqa: E731
    return (x0, x1), (pdfs(x0), pdfs(x1))


def test_optimal_is_exact_when_f_is_in_the_span_of_the_pdfs():
    (x0, x1), (p0, p1) = draws(64)
    f = lambda x: 3 + 2 * x  # noqa: E731 - ∫ = 4 = 3 p0 + 1 p1
    est = mis.estimate([f(x0), f(x1)], [p0, p1], estimator="optimal-direct", ridge=0.0)
    assert est.shape == (1,)
    assert abs(est[0] - 4.0) < 1e-9
    bal = mis.estimate([f(x0), f(x1)], [p0, p1], estimator="balance")
    assert abs(bal[0] - 4.0) > 1e-6


def test_balance_is_the_textbook_formula():
    (x0, x1), (p0, p1) = draws(200, seed=2)
    f = lambda x: np.stack([x * x, np.cos(x)], axis=-1)  # noqa: E731 - two channels
    est = mis.estimate([f(x0), f(x1)], [p0, p1], estimator="balance")
    by_hand = sum((f(x) / p.sum(axis=1, keepdims=True)).mean(axis=0)
                  for x, p in [(x0, p0), (x1, p1)])
    np.testing.assert_allclose(est, by_hand, rtol=1e-12)
    np.testing.assert_allclose(est, [1 / 3, np.sin(1.0)], rtol=0.05)


@pytest.mark.parametrize("estimator", mis.estimators())
def test_every_estimator_is_unbiased_enough(estimator):
    (x0, x1), (p0, p1) = draws(4000, seed=3)
    f = lambda x: np.exp(x)  # noqa: E731
    est = mis.estimate([f(x0), f(x1)], [p0, p1], estimator=estimator)
    assert abs(est[0] - (np.e - 1)) < 0.02


def test_several_draws_per_iteration():
    rng = np.random.default_rng(4)
    x = rng.random((100, 3))  # 3 uniform draws per iteration, one technique
    est = mis.estimate([x * x], [np.ones((100, 3, 1))], estimator="balance")
    np.testing.assert_allclose(est, [(x * x).mean()], rtol=1e-12)


def test_shape_errors():
    with pytest.raises(ValueError):
        mis.estimate([np.ones(5)], [np.ones((4, 1))])
    with pytest.raises(ValueError):
        mis.estimate([np.ones(5)], [np.ones((5, 1))], estimator="nonsense")


def test_method_is_the_older_name_of_estimator():
    x = np.linspace(0.05, 0.95, 10)
    p = np.stack([np.ones_like(x), 2 * x], axis=-1)
    a = mis.estimate([x, x], [p, p], estimator="power")
    b = mis.estimate([x, x], [p, p], method="power")
    assert np.array_equal(a, b) and mis.methods() == mis.estimators()
