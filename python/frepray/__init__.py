"""frepray from Python: FRep scenes rendered with optimal MIS.

Load a scene (a file, or a dict with the JSON schema of docs/scene-format.md), render any
range of samples into a :class:`RenderState` (per-pixel sums that merge exactly), read
its image as numpy, evaluate bare models, combine numpy samples with the ``mis``
estimators, and compare estimators.  See docs/python.md; renders across machines:
:mod:`frepray.distributed` (docs/distributed.md).
"""

from __future__ import annotations

import json
import math
import os
from typing import Any, Iterable, Mapping, Optional, Sequence, Tuple, Union



def _runtime_dir() -> None:
    """Gives Mesa's Vulkan drivers a runtime directory where the session has none (a
    container, a CI job): without one they print "XDG_RUNTIME_DIR is invalid or not set"
    whenever the GPU is touched. A private directory (mode 0700) under the temporary
    directory, as the `frepray` command makes; nothing changes when it cannot be made.
    Runs at import, before the extension opens any device."""
    if os.path.isdir(os.environ.get("XDG_RUNTIME_DIR", "")):
        return
    import tempfile

    try:
        uid = os.getuid()
        path = os.path.join(tempfile.gettempdir(), f"frepray-runtime-{uid}")
        try:
            os.mkdir(path, 0o700)
        except FileExistsError:
            pass
        st = os.stat(path)
        if os.path.isdir(path) and st.st_uid == uid and st.st_mode & 0o077 == 0:
            os.environ["XDG_RUNTIME_DIR"] = path
    except (AttributeError, OSError):
        pass


_runtime_dir()

from . import mis  # noqa: E402
from .denoise import denoise  # noqa: E402
from ._native import (  # noqa: E402
    Cancel,
    Cancelled,
    Error,
    Model,
    ModelError,
    RenderError,
    RenderState,
    Scene,
    SceneError,
    Viewer,
    bench,
    configure_gpu,
    exr_attributes,
    gpu_adapters,
    gpu_available,
    load,
    merge,
    model,
    read_exr,
    render,
)
from ._native import experiment as _experiment  # noqa: E402
from ._native import load_json as _load_json  # noqa: E402
from ._native import measure, summarize  # noqa: E402

__all__ = [
    "Error", "SceneError", "RenderError", "ModelError", "Cancelled", "Cancel", "Scene",
    "RenderState", "Model", "Viewer",
    "load", "load_dict", "render", "merge", "read_exr", "exr_attributes", "write_exr", "model",
    "mis", "experiment", "denoise", "measure", "summarize", "gpu_available", "gpu_adapters",
    "configure_gpu", "bench",
]


def _plain(value: Any) -> Any:
    """numpy scalars and arrays (and tuples) as JSON values."""
    if hasattr(value, "tolist"):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not a scene value")


def _key(path: str, key: Any) -> str:
    """``path.key`` as the scene errors print it (keys other than words quoted)."""
    k = str(key)
    if not (k and all(c.isascii() and (c.isalnum() or c in "_-") for c in k)):
        k = json.dumps(k)
    return f"{path}.{k}" if path else k


def _non_finite(value: Any, path: str = "") -> Optional[Tuple[str, float]]:
    """The key path and value of the first number that is not finite (JSON has none)."""
    if hasattr(value, "tolist"):
        value = value.tolist()
    if isinstance(value, float):
        return None if math.isfinite(value) else (path, value)
    if isinstance(value, Mapping):
        items: Iterable = ((_key(path, k), v) for k, v in value.items())
    elif isinstance(value, (list, tuple)):
        items = ((f"{path}[{i}]", v) for i, v in enumerate(value))
    else:
        return None
    for p, v in items:
        found = _non_finite(v, p)
        if found:
            return found
    return None


def load_dict(scene: Mapping[str, Any], base_dir: Union[str, os.PathLike, None] = None) -> Scene:
    """A scene given as a dict (the JSON schema; numpy values allowed).  Relative model
    and map paths are found in ``base_dir`` (default: the working directory).  Raises
    :class:`SceneError` whose ``key`` is the key path, e.g. ``objects[0].material``
    (also for a NaN or infinite number, which JSON cannot hold)."""
    try:
        text = json.dumps(scene, default=_plain, allow_nan=False)
    except ValueError:
        found = _non_finite(scene)
        if found is None:
            raise
        key, value = found
        message = f"expected a finite number, found {value}"
        err = SceneError(f"{key}: {message}")
        err.file, err.line, err.column, err.key, err.message = "", 0, 0, key, message
        raise err from None
    return _load_json(text, None if base_dir is None else os.fspath(base_dir))


def write_exr(state_or_image: Any, path: Union[str, os.PathLike]) -> None:
    """Writes a :class:`RenderState`'s image as a linear float32 EXR."""
    if isinstance(state_or_image, RenderState):
        state_or_image.write_exr(os.fspath(path))
    else:
        raise TypeError("write_exr takes a RenderState")


def experiment(
    scene: Scene,
    estimators: Sequence[str],
    spp: Iterable[int],
    *,
    out: Union[str, os.PathLike, None] = None,
    reference_spp: int = 256,
    reference: Union[str, os.PathLike, None] = None,
    reference_estimator: Optional[str] = None,
    baseline: str = "balance",
    seed: int = 0,
    repeats: int = 4,
    techniques: Optional[str] = None,
    integrator: Optional[str] = None,
    width: Optional[int] = None,
    height: Optional[int] = None,
    per_light: bool = False,
    pixel_center: bool = False,
    decompose: bool = False,
    max_depth: Optional[int] = None,
    min_depth: Optional[int] = None,
    hide_emitters: bool = False,
    beta: Optional[float] = None,
    cutoff: Optional[float] = None,
    ridge: Optional[float] = None,
    trained_grid: Optional[int] = None,
    trained_floor: Optional[float] = None,
    trained_spp: Optional[int] = None,
    threads: int = 0,
    pandas: Optional[bool] = None,
    cancel: Optional[Cancel] = None,
    budget: Optional[float] = None,
    practice: bool = False,
):
    """The estimator comparison of ``frepray experiment``: a reference (rendered with
    ``reference_spp`` samples, or the EXR ``reference``), then every estimator at every
    spp, each at ``repeats`` seeds.  Returns one record per (estimator, spp) with
    ``time_s``, ``mse``, ``rmse``, ``relmse``, 95 % intervals ``mse_ci``, ``rmse_ci``
    (``[lo, hi]``, None with one seed), ``trimmed_mse``, ``net_mse`` (less the reference's
    noise), ``cpu_s`` and, against ``baseline``, ``improvement`` (with
    ``improvement_ci``, ``improvement_trimmed``, ``median_pixel_ratio``), ``speed_up``
    (``speed_up_ci``), ``overhead`` (DESIGN.md §4) -- a pandas DataFrame when pandas is installed (or ``pandas=True``),
    else a list of dicts.  ``per_light``, ``pixel_center`` and ``decompose`` are the CLI's
    ``--per-light``, ``--pixel-center`` and ``--decompose`` (the last adds
    ``variance_jittered``, ``variance_centered`` and ``direction_share``); ``max_depth``,
    ``min_depth``, ``hide_emitters``, ``beta``, ``cutoff``, ``ridge``, ``trained_grid``,
    ``trained_floor``, ``trained_spp`` and ``threads`` are its flags of the same names
    (``threads=0``: every core).  ``out`` receives results.json/csv, summary.md, plots and
    images (a temporary folder when not given); a rerun into the same ``out`` resumes.
    Ctrl-C (KeyboardInterrupt) or ``cancel`` (a :class:`Cancel`; :class:`Cancelled`)
    stops it with what finished written to ``out``.  ``budget`` (processor seconds, the
    CLI's ``--budget``): every estimator renders the spp that fill it and the comparison
    is at equal time (``spp`` is then not used).  An estimator may bring its own
    techniques (``"power@light-bvh+bsdf"``); ``practice=True`` adds the best heuristic
    practice as baselines (the CLI's ``--practice``)."""
    import tempfile

    def run(folder: str):
        return _experiment(
            scene, folder, list(estimators), [int(s) for s in spp],
            reference_spp=reference_spp,
            reference=None if reference is None else os.fspath(reference),
            reference_estimator=reference_estimator, baseline=baseline, seed=seed,
            repeats=repeats, techniques=techniques, integrator=integrator,
            width=width, height=height, per_light=per_light, pixel_center=pixel_center,
            decompose=decompose, max_depth=max_depth, min_depth=min_depth,
            hide_emitters=hide_emitters, beta=beta, cutoff=cutoff, ridge=ridge,
            trained_grid=trained_grid, trained_floor=trained_floor,
            trained_spp=trained_spp, threads=threads, cancel=cancel, budget=budget,
            practice=practice)

    if out is None:
        with tempfile.TemporaryDirectory(prefix="frepray-experiment-") as folder:
            records = run(folder)
    else:
        records = run(os.fspath(out))
    return _table(records, pandas)


def _table(records: list, pandas: Optional[bool]):
    """Records as a DataFrame when asked for (or, by default, when pandas imports)."""
    if pandas is False:
        return records
    try:
        import pandas as pd
    except ImportError:
        if pandas:
            raise
        return records
    return pd.DataFrame.from_records(records)
