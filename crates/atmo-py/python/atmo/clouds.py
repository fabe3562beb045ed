"""Clouds lit by the sun: atmo's particle clouds (see docs/clouds.md) as numpy arrays.

A cloud is an ``(n, 6)`` float32 array of Gaussian particles, one a row: x, y, z (m,
world frame: x east, y up, z south), radius (m, three standard deviations), peak
extinction (1/m) and single-scattering albedo.
"""

from __future__ import annotations

from typing import Optional, Sequence

import numpy as np

from . import _atmo

__all__ = ["cumulus", "render"]


def cumulus(particles: int = 20_000, seed: int = 1, width: float = 1200.0,
            base: float = 1500.0) -> np.ndarray:
    """A cumulus from atmo's generator: ``particles`` particles, ``width`` metres
    across, its flat base ``base`` metres above the ground; ``seed`` picks the cloud."""
    return _atmo.cumulus(int(particles), int(seed), float(width), float(base))


def render(particles=None, sun_elevation: float = 25.0, sun_azimuth: float = 40.0,
           eye: Optional[Sequence[float]] = None,
           look_at: Optional[Sequence[float]] = None, width: int = 960,
           height: int = 540, fov: float = 40.0, scattering: str = "solve",
           sky: bool = True, resolution: int = 128) -> np.ndarray:
    """The cloud ``particles`` (an ``(n, 6)`` array; a ``cumulus()`` unless given) lit
    by the sun at ``sun_elevation`` and ``sun_azimuth`` (deg) and seen from ``eye``
    toward ``look_at`` (m; by default from 1.5 km west, 2.5 km south and 300 m below
    the cloud's centre, at it) with a vertical field of view ``fov`` (deg):
    ``height x width x 3`` float32 linear radiance, W m^-2 sr^-1.

    ``scattering`` is ``"solve"`` (every order: the transfer solve through the cloud,
    the nearest the path tracer; docs/clouds.md), ``"multiple"`` (every order: atmo's
    transfer table fitted to the path tracer) or ``"single"`` (the paper's); ``sky`` draws the Earth's sky, every order, behind the
    cloud, lighting it and hazing it (without: the sun alone, on black); ``resolution`` is the light buffer's side (16-512)."""
    if scattering not in ("multiple", "solve", "single"):
        raise ValueError(f"scattering: 'multiple', 'solve' or 'single', got {scattering!r}")
    cloud = cumulus() if particles is None else particles
    cloud = np.ascontiguousarray(np.asarray(cloud, dtype=np.float32))
    if cloud.ndim != 2:
        raise ValueError(f"particles: an (n, 6) array, got shape {cloud.shape}")
    point = (lambda p: None if p is None else [float(v) for v in p])
    return _atmo.render_clouds(cloud, float(sun_elevation), float(sun_azimuth), point(eye),
                               point(look_at), int(width), int(height), float(fov),
                               scattering, bool(sky), int(resolution))
