"""Multiple importance sampling for any integral sampled in numpy.

The multi-sample model (Veach 1997, §9.2.2): each of N iterations draws ``n_t`` samples
from every technique t.  For each technique give ``f[t]``, the integrand at its samples,
and ``pdfs[t]``, the pdfs of *all* T techniques at those samples; :func:`estimate`
combines them with a heuristic (balance, power, maximum, cutoff) or an optimal MIS
estimator (Kondapaneni et al. 2019; docs/mis.md) and returns the estimate of ∫ f.

>>> import numpy as np
>>> from frepray import mis
>>> rng = np.random.default_rng(1)
>>> u = rng.random((64, 2))
>>> x0, x1 = u[:, 0], np.sqrt(u[:, 1])          # uniform, and pdf 2x on [0, 1]
>>> f = lambda x: 3 + 2 * x                       # ∫₀¹ f = 4 = 3·p₀ + 1·p₁
>>> pdfs = lambda x: np.stack([np.ones_like(x), 2 * x], axis=-1)
>>> est = mis.estimate([f(x0), f(x1)], [pdfs(x0), pdfs(x1)], estimator="optimal-direct",
...                    ridge=0.0)
>>> round(float(est[0]), 9)                        # f is in the span of the pdfs
4.0
"""

from __future__ import annotations

from typing import Sequence

import numpy as np

from ._native import mis_estimate, mis_methods

__all__ = ["estimate", "estimators", "methods"]


def estimators() -> list:
    """The estimator names (as ``render(estimator=…)``, the scene file's ``estimator``
    and the CLI's ``--estimator`` take them)."""
    return list(mis_methods())


def methods() -> list:
    """The estimator names: the older name of :func:`estimators`."""
    return estimators()


def _shape(f: np.ndarray, p: np.ndarray, t: int, techniques: int):
    """``f`` as (N, n_t, C) and ``p`` as (N, n_t, T) from the shapes the docs allow:
    f (N,), (N, C) or (N, n_t, C) with p (N, T) or (N, n_t, T)."""
    f = np.asarray(f, dtype=np.float64)
    p = np.asarray(p, dtype=np.float64)
    if p.ndim == 1 and techniques == 1:
        p = p[:, None]
    if p.ndim == 2:
        p = p[:, None, :]
        if f.ndim == 1:
            f = f[:, None, None]
        elif f.ndim == 2:
            f = f[:, None, :]
    elif p.ndim == 3 and f.ndim == 2:
        f = f[:, :, None]
    if f.ndim != 3 or p.ndim != 3:
        raise ValueError(
            f"technique {t}: f has shape {f.shape} and pdfs {p.shape}; expected f (N,), "
            "(N, C) or (N, n_t, C) with pdfs (N, T) or (N, n_t, T)")
    return np.ascontiguousarray(f), np.ascontiguousarray(p)


def estimate(
    f: Sequence[np.ndarray],
    pdfs: Sequence[np.ndarray],
    estimator: str = "balance",
    *,
    beta: float = 2.0,
    cutoff: float = 0.5,
    ridge: float | None = None,
    warmup: int = 1,
    train: int = 8,
    method: str | None = None,
) -> np.ndarray:
    """The MIS estimate of ∫ f, float64 ``(C,)``.

    ``f[t]``: the integrand at technique t's samples, ``(N,)`` (one draw per iteration,
    one channel), ``(N, C)`` or ``(N, n_t, C)``.  ``pdfs[t]``: every technique's pdf at
    those samples, ``(N, T)`` or ``(N, n_t, T)``; a sample whose own pdf is 0 counts as
    failed.  ``estimator``: one of :func:`estimators` (``method``, its older name, is
    still taken); ``beta`` (power), ``cutoff``, ``ridge`` (optimal; ``None``: the
    estimator's default, 0.1, or 1 for ``optimal-uncorrelated``), ``warmup``
    (progressive), ``train`` (full) are the estimators' parameters.
    """
    if method is not None:
        estimator = method
    if len(f) != len(pdfs):
        raise ValueError(f"{len(f)} arrays of f but {len(pdfs)} of pdfs")
    shaped = [_shape(a, b, t, len(f)) for t, (a, b) in enumerate(zip(f, pdfs))]
    return mis_estimate(
        estimator, [a for a, _ in shaped], [b for _, b in shaped], beta=beta, cutoff=cutoff,
        ridge=ridge, warmup=warmup, train=train)
