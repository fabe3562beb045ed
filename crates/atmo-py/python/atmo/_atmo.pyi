# Types of the extension module; the documented API is atmo's (__init__.py, shafts.py).
from os import PathLike
from typing import List, Optional, Tuple, TypedDict, Union

import numpy as np
import numpy.typing as npt

F64 = npt.NDArray[np.float64]
# Sun elevation (deg), altitude (m), azimuth from the sun's and elevation (deg), flat.
Points = Tuple[F64, F64, F64, F64]


class Look(TypedDict):
    width: int
    height: int
    fov_deg: float
    azimuth_deg: float
    elevation_deg: float
    sun_disc: bool


class Sky:
    def __init__(self, preset: Optional[str] = None,
                 toml_path: Optional[Union[str, PathLike]] = None, order: str = "all",
                 ozone: Optional[bool] = None) -> None: ...
    @property
    def wavelengths_nm(self) -> npt.NDArray[np.float64]: ...
    @property
    def name(self) -> str: ...
    @property
    def order(self) -> str: ...
    @property
    def solar_irradiance(self) -> npt.NDArray[np.float64]: ...
    def optical_depths(self, altitude_m: float) -> Tuple[npt.NDArray[np.float64],
                                                        npt.NDArray[np.float64],
                                                        npt.NDArray[np.float64]]: ...
    def radiance(self, points: Points) -> npt.NDArray[np.float32]: ...
    def render(self, sun_elevation_deg: float, sun_azimuth_deg: float, altitude_m: float,
               look: Look) -> npt.NDArray[np.float32]: ...
    def irradiance(self, sun_elevation_deg: npt.NDArray[np.float64],
                   sun_azimuth_deg: npt.NDArray[np.float64], altitude_m: float,
                   normals: npt.NDArray[np.float64]
                   ) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32],
                              npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...

class SkyTable:
    def __init__(self, path: Union[str, PathLike]) -> None: ...
    @property
    def name(self) -> str: ...
    @property
    def sun_elevation_range(self) -> Tuple[float, float]: ...
    @property
    def altitude_range(self) -> Tuple[float, float]: ...
    def radiance(self, points: Points) -> npt.NDArray[np.float32]: ...
    def render(self, sun_elevation_deg: float, sun_azimuth_deg: float, altitude_m: float,
               look: Look) -> npt.NDArray[np.float32]: ...

def sun_position(latitude_deg: float, longitude_deg: float, altitude_m: float,
                 unix_ns: npt.NDArray[np.int64]
                 ) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64],
                            npt.NDArray[np.float64]]: ...
def render_shafts(path: Union[str, PathLike], time_s: float = 0.0
                  ) -> npt.NDArray[np.float32]: ...
def cumulus(particles: int, seed: int, width_m: float, base_m: float
            ) -> npt.NDArray[np.float32]: ...
def render_clouds(particles: npt.NDArray[np.float32], sun_elevation_deg: float,
                  sun_azimuth_deg: float, eye: Optional[list], target: Optional[list],
                  width: int, height: int, fov_deg: float, scattering: str, sky: bool,
                  resolution: int) -> npt.NDArray[np.float32]: ...
def presets() -> List[str]: ...
