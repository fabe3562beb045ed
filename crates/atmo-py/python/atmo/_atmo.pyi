# Types of the extension module; the documented API is atmo's (__init__.py, shafts.py).
from os import PathLike
from typing import Optional, Tuple, Union

import numpy as np
import numpy.typing as npt

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
    def radiance(self, sun_elevation_deg: npt.NDArray[np.float64],
                 altitude_m: npt.NDArray[np.float64],
                 azimuth_from_sun_deg: npt.NDArray[np.float64],
                 elevation_deg: npt.NDArray[np.float64]) -> npt.NDArray[np.float32]: ...
    def render(self, sun_elevation_deg: float, sun_azimuth_deg: float, altitude_m: float,
               width: int, height: int, fov_deg: float, view_azimuth_deg: float,
               view_elevation_deg: float, sun_disc: bool) -> npt.NDArray[np.float32]: ...
    def irradiance(self, sun_elevation_deg: npt.NDArray[np.float64],
                   sun_azimuth_deg: npt.NDArray[np.float64], altitude_m: float,
                   normals: npt.NDArray[np.float64]
                   ) -> Tuple[npt.NDArray[np.float32], npt.NDArray[np.float32],
                              npt.NDArray[np.float64], npt.NDArray[np.float64]]: ...

def sun_position(latitude_deg: float, longitude_deg: float, altitude_m: float,
                 unix_ns: npt.NDArray[np.int64]
                 ) -> Tuple[npt.NDArray[np.float64], npt.NDArray[np.float64],
                            npt.NDArray[np.float64]]: ...
def render_shafts(path: Union[str, PathLike], time_s: float = 0.0
                  ) -> npt.NDArray[np.float32]: ...
def presets() -> list[str]: ...
