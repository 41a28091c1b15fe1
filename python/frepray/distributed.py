"""Renders that outgrow one machine, on Ray.

A render is split into sample ranges (docs/render-state.md): task k renders samples
``[a_k, b_k)`` of every pixel and returns its serialised :class:`~frepray.RenderState`;
the driver merges the parts in range order.  Sample ``i`` of a pixel draws its random
numbers from ``(seed, pixel, i)`` alone, so the parts hold exactly the samples of one
render of the whole range: the per-pixel sample counts are identical, the sums equal
to ~1e-12 relative (additions in another order), and for the same split the result is
bit-identical however the tasks are scheduled, retried or placed.  A task whose worker
dies, or that raises OSError, is retried (``max_retries``).  See docs/distributed.md.

Scenes travel to the workers as their source (a file path, which must exist on every
node, or the dict as JSON).  ``ray.init()`` is called with defaults if Ray is not
initialised yet.
"""

from __future__ import annotations

import os
import time
from typing import Any, Callable, List, Optional, Sequence, Tuple

from . import _native
from ._native import RenderState, Scene

__all__ = ["split", "render", "experiment", "REFERENCE_SEED_MASK"]

#: XORed into the seed of a rendered reference (as ``frepray experiment`` does), so that
#: its noise is independent of the measured renders'.
REFERENCE_SEED_MASK = 0x9E3779B97F4A7C15


def split(start: int, end: int, tasks: int) -> List[Tuple[int, int]]:
    """``[start, end)`` cut into at most ``tasks`` contiguous, non-empty ranges of
    nearly equal size, in order."""
    if not start < end:
        raise ValueError(f"empty sample range [{start}, {end})")
    tasks = max(1, min(int(tasks), end - start))
    n = end - start
    bounds = [start + (n * k) // tasks for k in range(tasks + 1)]
    return [(a, b) for a, b in zip(bounds, bounds[1:])]


def _ray():
    import ray

    if not ray.is_initialized():
        ray.init()
    return ray


def _render_part(scene: Scene, a: int, b: int, options: dict, kill_marker: Optional[str]):
    """One task: samples ``[a, b)``, as bytes.  ``kill_marker`` (tests only): if that
    file does not exist yet, create it and kill this worker process after rendering,
    before returning -- a task lost mid-way, which Ray must retry."""
    state = _native.render(scene, samples=(a, b), **options)
    if kill_marker is not None and not os.path.exists(kill_marker):
        with open(kill_marker, "w") as f:
            f.write(f"killed the task of samples [{a}, {b}) in process {os.getpid()}\n")
        os._exit(1)
    return state.to_bytes()


def _remote(fn, max_retries: int, num_cpus: float):
    # A lost worker is always retried; of exceptions only the transient kind (a file
    # system or network hiccup): a frepray.Error is deterministic and would recur.
    ray = _ray()
    return ray.remote(max_retries=max_retries, retry_exceptions=[OSError],
                      num_cpus=num_cpus)(fn)


def render(
    scene: Scene,
    spp: Optional[int] = None,
    tasks: int = 4,
    *,
    samples: Optional[Tuple[int, int]] = None,
    max_retries: int = 3,
    num_cpus: float = 1,
    threads: Optional[int] = None,
    progress: Optional[Callable[[int, int], None]] = None,
    kill_marker: Optional[str] = None,
    **options: Any,
) -> RenderState:
    """Renders samples ``samples`` (default ``(0, spp)``, spp from the scene when not
    given) of ``scene`` as ``tasks`` Ray tasks of contiguous sample ranges and merges
    them.  Other keywords are :func:`frepray.render`'s options (seed, estimator,
    techniques, integrator, width, height, …).  Each task asks Ray for ``num_cpus`` CPUs
    and renders on ``threads`` threads (default ``num_cpus``).  ``progress(done, total)``
    is called as parts arrive.

    Ctrl-C cancels the unfinished tasks and raises KeyboardInterrupt whose ``state`` is
    the merge of the parts that finished, marked partial (None if none had)."""
    if samples is None:
        if spp is None:
            spp = int(scene.settings["spp"])
        samples = (0, int(spp))
    elif spp is not None:
        options["spp"] = spp
    options["threads"] = int(threads if threads is not None else max(1, int(num_cpus)))
    ray = _ray()
    task = _remote(_render_part, max_retries, num_cpus)
    ranges = split(samples[0], samples[1], tasks)
    refs = [task.remote(scene, a, b, options, kill_marker) for a, b in ranges]
    return _native.merge(_gather(ray, refs, progress))


def _gather(ray, refs: list, progress: Optional[Callable[[int, int], None]]) -> list:
    """The tasks' states in the order of ``refs``.  On KeyboardInterrupt the unfinished
    tasks are cancelled and the exception's ``state`` is the merge of the finished parts,
    marked partial (None if none finished)."""
    done: dict = {}
    pending = list(refs)
    try:
        while pending:
            # A short timeout keeps Ctrl-C prompt while Ray waits.
            ready, pending = ray.wait(pending, num_returns=1, timeout=0.1)
            for r in ready:
                done[r] = RenderState.from_bytes(bytes(ray.get(r)))
                if progress is not None:
                    progress(len(done), len(refs))
    except KeyboardInterrupt as e:
        if pending:
            ready, pending = ray.wait(pending, num_returns=len(pending), timeout=0)
            for r in pending:
                ray.cancel(r)
            for r in ready:
                try:
                    done[r] = RenderState.from_bytes(bytes(ray.get(r, timeout=0)))
                except Exception:  # noqa: BLE001 - a failed part is left out, as unfinished
                    pass
        parts = [done[r] for r in refs if r in done]
        e.state = _native.merge(parts) if parts else None
        if e.state is not None:
            e.state.mark_partial()
        raise
    return [done[r] for r in refs]


def _render_timed(scene: Scene, estimator: str, spp: int, seed: int, options: dict):
    """One render of an experiment: (image float64 (h, w, 3+), seconds)."""
    t = time.perf_counter()
    state = _native.render(scene, spp=spp, seed=seed, estimator=estimator, **options)
    return state.image_f64()[:, :, :3].copy(), time.perf_counter() - t


def experiment(
    scene: Scene,
    estimators: Sequence[str],
    spp: Sequence[int],
    *,
    reference_spp: int = 256,
    reference: Optional[RenderState] = None,
    reference_estimator: Optional[str] = None,
    reference_tasks: int = 4,
    baseline: str = "balance",
    seed: int = 0,
    repeats: int = 1,
    max_retries: int = 3,
    num_cpus: float = 1,
    pandas: Optional[bool] = None,
    **options: Any,
):
    """The estimator comparison with every render a Ray task: the reference (unless
    given) split over ``reference_tasks`` tasks, then each (estimator, spp, repeat) as
    one task.  The tables are :func:`frepray.summarize`'s: the same points, 95 %
    intervals (with ``repeats`` ≥ 2) and Improvement / Speed Up / Overhead as
    :func:`frepray.experiment` gives; times are each task's render time.  Returns the
    same records (or DataFrame)."""
    from . import _table

    ray = _ray()
    options["threads"] = max(1, int(num_cpus))
    if reference is None:
        ref_options = dict(options)
        ref_options["estimator"] = reference_estimator or baseline
        reference = render(
            scene, reference_spp, reference_tasks, seed=seed ^ REFERENCE_SEED_MASK,
            max_retries=max_retries, num_cpus=num_cpus, **ref_options)
    ref = reference.image_f64()[:, :, :3].copy()
    names = [baseline] + [e for e in estimators if e != baseline]
    seeds = [seed + r for r in range(repeats)]
    task = _remote(_render_timed, max_retries, num_cpus)
    jobs = [(e, s, r) for e in names for s in sorted(set(spp)) for r in seeds]
    results = ray.get([task.remote(scene, e, s, r, options) for e, s, r in jobs])
    measured = []
    for (e, s, r), (img, secs) in zip(jobs, results):
        m = _native.measure(img, ref)
        measured.append(dict(m, estimator=e, spp=s, seed=r, time_s=secs))
    # The library's tables (frepray::experiment::summarize): the points averaged over
    # seeds with their intervals, and the comparisons, as frepray.experiment gives them.
    rows = _native.summarize(measured, baseline)
    return _table(rows, pandas)
