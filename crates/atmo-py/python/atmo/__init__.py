"""atmo for Python: light scattered in the air as numpy arrays.

The sky with every scattering order (radiance per wavelength along any directions, for
any suns, at any altitude), irradiance on surfaces of any orientation, the sun's
position at a place and time (NREL SPA), and pictures of the sky, of light shafts in
haze (``atmo.shafts``) and of clouds (``atmo.clouds``).

Units are in the argument names or said in each docstring: angles in degrees, lengths
in metres, radiance in W m^-2 sr^-1 nm^-1, irradiance in W m^-2 nm^-1, illuminance in
lux. The world frame is atmo's: x east, y up, z south; azimuths clockwise from north.

>>> import atmo
>>> sky = atmo.Sky("earth")
>>> sky.radiance(sun_elevation=10, azimuth=180, elevation=[5, 30, 90]).shape
(3, 6)
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Optional, Sequence, Union

import numpy as np

from . import _atmo
from . import clouds, shafts  # noqa: F401  (atmo.clouds, atmo.shafts)

__all__ = ["Sky", "SkyTable", "Irradiance", "SunPosition", "sun_position", "presets", "clouds", "shafts"]

ArrayLike = Union[float, Sequence[float], np.ndarray]


def presets() -> list:
    """The names of the embedded atmospheres, the default (``earth``) first."""
    return list(_atmo.presets())


def _flat(*arrays: ArrayLike):
    """The arguments broadcast together: their common shape and each as a contiguous
    one-dimensional float64 array."""
    broadcast = np.broadcast_arrays(*[np.asarray(a, dtype=np.float64) for a in arrays])
    shape = broadcast[0].shape
    return shape, [np.ascontiguousarray(b.reshape(-1)) for b in broadcast]


@dataclass(frozen=True)
class Irradiance:
    """Irradiance on a surface: per wavelength (the last axis, at
    ``Sky.wavelengths_nm``), W m^-2 nm^-1, and as illuminance, lux."""

    direct: np.ndarray
    """The sun's disc through the atmosphere, times the cosine of its incidence."""
    diffuse: np.ndarray
    """The sky and the lit ground over the surface's hemisphere, every order."""
    direct_lux: np.ndarray
    diffuse_lux: np.ndarray

    @property
    def global_(self) -> np.ndarray:
        """Direct plus diffuse, per wavelength."""
        return self.direct + self.diffuse

    @property
    def global_lux(self) -> np.ndarray:
        """Direct plus diffuse, lux."""
        return self.direct_lux + self.diffuse_lux


class Sky:
    """The sky of one atmosphere by atmo's shell method.

    ``atmosphere`` is an embedded preset's name (``atmo.presets()``: ``earth``, the
    default, six wavelengths; ``earth-spectral``, 48 wavelengths from 360 to 830 nm for
    colour work; ``paper`` and others) or the path of an atmosphere TOML file.
    ``order`` is ``"all"`` (every order, the default) or the highest scattering order;
    ``ozone`` turns an atmosphere's ozone layer on or off.

    The first call at an altitude computes the light at its shells (about a second
    with every order); later calls there only sum along the asked directions.
    """

    def __init__(self, atmosphere: str = "earth", order: Union[str, int] = "all",
                 ozone: Optional[bool] = None):
        path = str(atmosphere)
        is_file = path.endswith(".toml")
        self._sky = _atmo.Sky(
            preset=None if is_file else path,
            toml_path=path if is_file else None,
            order=str(order),
            ozone=ozone,
        )

    @classmethod
    def from_toml(cls, path, order: Union[str, int] = "all",
                  ozone: Optional[bool] = None) -> "Sky":
        """The sky of the atmosphere file at ``path``."""
        path = str(path)
        if not path.endswith(".toml"):
            raise ValueError(f"path: an atmosphere file ending in .toml, got {path!r}")
        return cls(path, order, ozone)

    @staticmethod
    def from_table(path) -> "SkyTable":
        """The sky drawn from a skylight table file (``atmo precompute sky``):
        linear sRGB for any sun and altitude in its ranges, a map in well under a
        millisecond. See ``SkyTable``."""
        return SkyTable(path)

    @property
    def wavelengths_nm(self) -> np.ndarray:
        """The wavelengths the spectra are given at, nm."""
        return self._sky.wavelengths_nm

    @property
    def name(self) -> str:
        """The atmosphere's name."""
        return self._sky.name

    @property
    def solar_irradiance(self) -> np.ndarray:
        """The sun's irradiance at the top of the atmosphere, W m^-2 nm^-1, at
        ``wavelengths_nm``."""
        return self._sky.solar_irradiance

    def optical_depths(self, altitude: float = 0.0) -> dict:
        """The vertical optical depth from ``altitude`` metres to space per wavelength:
        ``{"rayleigh": ..., "aerosols": ... (extinction), "ozone": ... (absorption)}``."""
        rayleigh, aerosols, ozone = self._sky.optical_depths(float(altitude))
        return {"rayleigh": rayleigh, "aerosols": aerosols, "ozone": ozone}

    @property
    def order(self) -> str:
        """The highest scattering order, ``"all"`` or a number."""
        return self._sky.order

    def __repr__(self) -> str:
        return f"atmo.Sky({self.name!r}, order={self.order!r})"

    def radiance(self, sun_elevation: ArrayLike, azimuth: ArrayLike,
                 elevation: ArrayLike, altitude: ArrayLike = 0.0,
                 sun_azimuth: ArrayLike = 180.0) -> np.ndarray:
        """Radiance per wavelength, W m^-2 sr^-1 nm^-1, seen ``altitude`` metres high
        looking toward ``azimuth`` (deg clockwise from north) and ``elevation`` (deg;
        below the horizon: the lit ground), the sun at ``sun_elevation`` and
        ``sun_azimuth`` (deg). The sun's disc itself is not included.

        The arguments broadcast as numpy arrays do; the result has their shape plus one
        last axis of wavelengths (``wavelengths_nm``).
        """
        return _radiance(self._sky, sun_elevation, azimuth, elevation, altitude, sun_azimuth)

    def render(self, sun_elevation: float, width: int = 640, height: int = 360,
               fov: float = 60.0, sun_azimuth: float = 180.0, altitude: float = 0.0,
               view_azimuth: Optional[float] = None, view_elevation: float = 10.0,
               sun_disc: bool = True) -> np.ndarray:
        """The sky as a pinhole camera sees it: ``height x width x 3`` float32 linear
        sRGB radiance, W m^-2 sr^-1. ``fov`` is the vertical field of view, deg; the
        camera looks toward ``view_azimuth`` (the sun's azimuth unless given) and
        ``view_elevation``, deg."""
        return _render(self._sky, sun_elevation, width, height, fov, sun_azimuth, altitude,
                       view_azimuth, view_elevation, sun_disc)

    def irradiance(self, sun_elevation: ArrayLike, normal=(0.0, 1.0, 0.0),
                   sun_azimuth: ArrayLike = 180.0, altitude: float = 0.0) -> Irradiance:
        """Irradiance on a surface facing ``normal`` (world frame: x east, y up,
        z south; (0, 1, 0) is horizontal) at ``altitude`` metres, the sun at
        ``sun_elevation`` and ``sun_azimuth`` (deg): direct, diffuse and global, per
        wavelength and in lux. Suns and normals broadcast (a normal's three components
        are its last axis)."""
        normal = np.asarray(normal, dtype=np.float64)
        if normal.shape[-1:] != (3,):
            raise ValueError(f"normal: a vector of three components (x, y, z), "
                             f"got shape {normal.shape}")
        elevation = np.asarray(sun_elevation, dtype=np.float64)
        azimuth = np.asarray(sun_azimuth, dtype=np.float64)
        shape = np.broadcast_shapes(elevation.shape, azimuth.shape, normal.shape[:-1])

        def flat(a, tail=()):
            return np.ascontiguousarray(np.broadcast_to(a, shape + tail).reshape(-1))

        sun, sun_az, normals = flat(elevation), flat(azimuth), flat(normal, (3,))
        direct, diffuse, direct_lux, diffuse_lux = self._sky.irradiance(
            sun, sun_az, float(altitude), normals)
        n = direct.shape[-1]
        return Irradiance(direct.reshape(shape + (n,)), diffuse.reshape(shape + (n,)),
                          direct_lux.reshape(shape), diffuse_lux.reshape(shape))


def _radiance(source, sun_elevation, azimuth, elevation, altitude, sun_azimuth):
    """``source.radiance`` over the broadcast arguments, in their shape plus one last
    axis (wavelengths or RGB)."""
    shape, (sun, az, el, h, sun_az) = _flat(
        sun_elevation, azimuth, elevation, altitude, sun_azimuth)
    flat = source.radiance((sun, h, np.ascontiguousarray(az - sun_az), el))
    return flat.reshape(shape + (flat.shape[-1],))


def _render(source, sun_elevation, width, height, fov, sun_azimuth, altitude,
            view_azimuth, view_elevation, sun_disc):
    look = {"width": int(width), "height": int(height), "fov_deg": float(fov),
            "azimuth_deg": float(sun_azimuth if view_azimuth is None else view_azimuth),
            "elevation_deg": float(view_elevation), "sun_disc": bool(sun_disc)}
    return source.render(float(sun_elevation), float(sun_azimuth), float(altitude), look)


class SkyTable:
    """A skylight table (``atmo precompute sky -o FILE.atmo-sky``, sky section 4):
    the sky in linear sRGB for any sun and viewpoint altitude inside its ranges, each
    map in well under a millisecond, within the table's stated error of the model it
    was computed from. It holds the sky above the horizon: below, 0."""

    def __init__(self, path):
        self._table = _atmo.SkyTable(os.fspath(path))

    @property
    def name(self) -> str:
        """The atmosphere's name."""
        return self._table.name

    @property
    def sun_elevation_range(self) -> tuple:
        """The sun elevations the table covers, deg."""
        return self._table.sun_elevation_range

    @property
    def altitude_range(self) -> tuple:
        """The viewpoint altitudes the table covers, m."""
        return self._table.altitude_range

    def __repr__(self) -> str:
        return f"atmo.SkyTable({self.name!r})"

    def radiance(self, sun_elevation: ArrayLike, azimuth: ArrayLike,
                 elevation: ArrayLike, altitude: ArrayLike = 0.0,
                 sun_azimuth: ArrayLike = 180.0) -> np.ndarray:
        """Linear sRGB radiance, W m^-2 sr^-1, as ``Sky.radiance`` takes its
        arguments: their broadcast shape plus a last axis of 3."""
        return _radiance(self._table, sun_elevation, azimuth, elevation, altitude,
                         sun_azimuth)

    def render(self, sun_elevation: float, width: int = 640, height: int = 360,
               fov: float = 60.0, sun_azimuth: float = 180.0, altitude: float = 0.0,
               view_azimuth: Optional[float] = None, view_elevation: float = 10.0,
               sun_disc: bool = True) -> np.ndarray:
        """The sky as a pinhole camera sees it, from the table (as ``Sky.render``)."""
        return _render(self._table, sun_elevation, width, height, fov, sun_azimuth,
                       altitude, view_azimuth, view_elevation, sun_disc)


@dataclass(frozen=True)
class SunPosition:
    """The sun seen from a place, deg, one value per time."""

    elevation: np.ndarray
    """Geometric elevation of the sun's centre (no refraction)."""
    apparent_elevation: np.ndarray
    """The same through a standard atmosphere's refraction (1010 hPa, 10 C)."""
    azimuth: np.ndarray
    """Clockwise from north, in [0, 360)."""


def _unix_ns(times) -> np.ndarray:
    """Times as int64 nanoseconds since 1970-01-01 UTC: numpy datetime64 (taken as
    UTC), a pandas DatetimeIndex or Timestamp (zone-aware ones converted to UTC),
    or datetime objects."""
    try:
        import pandas as pd  # optional: only to read pandas times
    except ImportError:  # pragma: no cover - pandas is optional
        pd = None
    if pd is not None and isinstance(times, (pd.DatetimeIndex, pd.Series, pd.Timestamp)):
        index = pd.DatetimeIndex([times] if isinstance(times, pd.Timestamp) else times)
        if index.tz is not None:
            index = index.tz_convert("UTC").tz_localize(None)
        return np.ascontiguousarray(index.values.astype("datetime64[ns]").astype(np.int64))
    array = np.asarray(times)
    if array.dtype.kind == "O":
        import datetime as dt
        array = np.array([t.astimezone(dt.timezone.utc).replace(tzinfo=None)
                          if t.tzinfo else t for t in array.reshape(-1)],
                         dtype="datetime64[ns]").reshape(array.shape)
    if array.dtype.kind != "M":
        raise ValueError("times: numpy datetime64 values, a pandas DatetimeIndex, "
                         f"or datetime objects are expected, got dtype {array.dtype}")
    return np.ascontiguousarray(array.astype("datetime64[ns]").astype(np.int64).reshape(-1))


def sun_position(latitude: float, longitude: float, times,
                 altitude: float = 0.0) -> SunPosition:
    """The sun's position at ``latitude`` and ``longitude`` (deg, north and east
    positive), ``altitude`` metres above sea level, at ``times`` (numpy datetime64 in
    UTC, a pandas DatetimeIndex, or datetime objects), by NREL's Solar Position
    Algorithm. Arrays in the shape of ``times``."""
    ns = _unix_ns(times)
    shape = np.shape(times) if isinstance(times, np.ndarray) else (ns.size,)
    if np.isscalar(times) or isinstance(times, np.datetime64):
        shape = ()
    elevation, apparent, azimuth = _atmo.sun_position(
        float(latitude), float(longitude), float(altitude), ns)
    return SunPosition(elevation.reshape(shape), apparent.reshape(shape),
                       azimuth.reshape(shape))
