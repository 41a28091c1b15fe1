"""Denoised previews: Intel Open Image Denoise (through the `pyoidn` package, which ships
the library in its wheel) fed with a render's colour and, where the render kept them,
its albedo and normal AOVs (``aovs=["albedo", "normal"]``).

A denoised image is biased: it is for looking at, never for measuring. It is returned
as a new array (the render state is untouched) and written only where asked, to its own
file, labelled in the EXR header (``frepray.denoised``); experiments never denoise.
"""

from __future__ import annotations

import os
from typing import Any, Optional, Union

import numpy as np

from ._native import RenderState, _write_rgb_exr

__all__ = ["denoise"]

_ALBEDO = ("albedo.R", "albedo.G", "albedo.B")
_NORMAL = ("normal.X", "normal.Y", "normal.Z")


def _stack(aovs: dict, names: tuple) -> Optional[np.ndarray]:
    if not all(n in aovs for n in names):
        return None
    return np.ascontiguousarray(np.stack([aovs[n] for n in names], axis=-1), dtype=np.float32)


def denoise(state: RenderState, out: Union[str, os.PathLike, None] = None, *,
            quality: str = "high") -> np.ndarray:
    """The state's image denoised by Open Image Denoise's ``RT`` filter (HDR), float32
    ``(h, w, 3)``, with the albedo and normal AOVs as guides where the state has them.
    ``out`` (``.exr``): also written there, its header recording the render's settings
    and ``frepray.denoised``. Needs ``pyoidn`` (``pip install pyoidn``)."""
    try:
        import pyoidn
    except ImportError:
        raise ImportError(
            "frepray.denoise needs Open Image Denoise's Python binding: pip install pyoidn"
        ) from None
    if not isinstance(state, RenderState):
        raise TypeError("denoise takes a RenderState")
    color = np.ascontiguousarray(state.image(), dtype=np.float32)
    aovs = state.aovs()
    albedo, normal = _stack(aovs, _ALBEDO), _stack(aovs, _NORMAL)
    if albedo is None:
        normal = None  # OIDN takes a normal only with an albedo
    result = pyoidn.denoise(color, albedo, normal, hdr=True, quality=quality)
    result = np.maximum(np.asarray(result, dtype=np.float32), 0.0)
    if out is not None:
        path = os.fspath(out)
        if not path.lower().endswith(".exr"):
            raise ValueError(f"{path}: a denoised image is written as .exr")
        guides = " + ".join(g for g, a in (("albedo", albedo), ("normal", normal)) if a is not None)
        label = (f"Intel Open Image Denoise {pyoidn.version.oidn_version}, RT filter, HDR, "
                 f"quality {quality}, guides: {guides or 'none'}")
        attributes = dict(state.attributes())
        attributes["frepray.denoised"] = label
        _write_rgb_exr(path, result, attributes)
    return result
