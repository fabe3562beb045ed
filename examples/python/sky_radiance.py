"""The sky's radiance along the solar almucantar at three wavelengths, and the daylight
on a horizontal surface over a summer's day, from atmo's Python package.

    pip install ./crates/atmo-py matplotlib
    python examples/python/sky_radiance.py docs/

writes python-almucantar.png and python-daylight.png into the folder given (the
current one by default).
"""

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only, no window
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import atmo  # noqa: E402

out = Path(sys.argv[1] if len(sys.argv) > 1 else ".")

# The Earth at 48 wavelengths, every scattering order, ozone: radiance at any
# wavelength in 360-830 nm by interpolation between its samples.
sky = atmo.Sky("earth-spectral")
wavelengths = sky.wavelengths_nm

# The almucantar: the circle of the sky at the sun's elevation, azimuth measured from
# the sun's. Many suns and azimuths in one call (numpy broadcasting).
suns = np.array([5.0, 20.0, 45.0])
azimuth = np.linspace(0.0, 180.0, 181)
L = sky.radiance(sun_elevation=suns[:, None], azimuth=azimuth[None, :] + 180.0,
                 elevation=suns[:, None], sun_azimuth=180.0)   # (suns, azimuths, wavelengths)
fig, axes = plt.subplots(1, 3, figsize=(12, 3.6), sharey=True)
for ax, k in zip(axes, range(len(suns))):
    for nm, colour in [(450, "tab:blue"), (550, "tab:green"), (650, "tab:red")]:
        at = np.array([np.interp(nm, wavelengths, spectrum) for spectrum in L[k]])
        ax.semilogy(azimuth, at, color=colour, label=f"{nm} nm")
    ax.set_title(f"sun at {suns[k]:g} deg")
    ax.set_xlabel("azimuth from the sun, deg")
    ax.grid(True, which="both", alpha=0.3)
axes[0].set_ylabel("radiance, W m$^{-2}$ sr$^{-1}$ nm$^{-1}$")
axes[0].legend()
fig.suptitle("The solar almucantar at sea level (atmo, every order, ozone)")
fig.tight_layout()
fig.savefig(out / "python-almucantar.png", dpi=110)

# A day of daylight at Golden, Colorado (NREL's home) on the summer solstice: the sun
# from SPA, then direct and diffuse illuminance on a horizontal surface.
times = np.arange("2026-06-21T11:00", "2026-06-22T04:00", 10, dtype="datetime64[m]")
sun = atmo.sun_position(39.74, -105.18, times, altitude=1829.0)
up = sun.elevation > 0.5
day = atmo.Sky("earth")
E = day.irradiance(sun_elevation=sun.elevation[up], sun_azimuth=sun.azimuth[up],
                   altitude=1829.0)
hours = (times[up] - np.datetime64("2026-06-21T06:00")) / np.timedelta64(1, "h")
fig, ax = plt.subplots(figsize=(7, 4))
ax.plot(hours, E.global_lux / 1e3, "k", label="global")
ax.plot(hours, E.direct_lux / 1e3, "tab:orange", label="direct (the sun)")
ax.plot(hours, E.diffuse_lux / 1e3, "tab:blue", label="diffuse (the sky)")
ax.set_xlabel("local time (MDT, UTC-6), h")
ax.set_ylabel("illuminance on a horizontal surface, klx")
ax.set_title("Clear-sky daylight at Golden, CO, 21 June (atmo)")
ax.grid(True, alpha=0.3)
ax.legend()
fig.tight_layout()
fig.savefig(out / "python-daylight.png", dpi=110)
print(f"noon: global {E.global_lux.max():.0f} lx, diffuse {E.diffuse_lux.max():.0f} lx")
