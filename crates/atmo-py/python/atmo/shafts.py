"""Light shafts in haze: a scene file (see docs/shafts.md) drawn by the sample planes."""

from __future__ import annotations

import os

import numpy as np

from . import _atmo

__all__ = ["render"]


def render(scene: "str | os.PathLike", time: float = 0.0) -> np.ndarray:
    """The scene file at ``scene`` drawn by the sample planes on the CPU, its moving
    heads posed ``time`` seconds into its show: ``height x width x 3`` float32 linear
    radiance in the scene's unit per m^2 (cd/m^2 for candela scenes). Gobo, mesh and
    photometric paths in the file are relative to its folder."""
    return _atmo.render_shafts(os.fspath(scene), float(time))
