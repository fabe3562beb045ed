"""The direct and diffuse sunlight against Bird and Riordan's SPECTRL2 (pvlib), a
clear-sky spectral model no one here wrote, for the same optical depths.

SPECTRL2 computes each constituent's optical depth from its own formulas (Rayleigh
from the pressure, ozone from its cross sections and the column in atm-cm); atmo's
`earth-spectral` has Bruneton's Rayleigh coefficients (8 % above SPECTRL2's at 550
nm, with another spectral shape) and Serdyuchenko's ozone. To compare the transfer and
not the coefficients, SPECTRL2 is run for each wavelength with the pressure and the
ozone column that give atmo's vertical optical depths there, and the aerosols' depth
(atmo's, wavelength-independent: Angstrom alpha 0) and albedo; no water vapour. The
top-of-atmosphere spectra differ too (ASTM G-173 in 10 nm bins against SPECTRL2's
own: up to 5 % a bin), so the direct light is compared as a transmittance.
"""

import numpy as np
import pytest

import atmo

pvlib = pytest.importorskip("pvlib")

ELEVATIONS = [10.0, 20.0, 30.0, 45.0, 60.0, 90.0]


def rayleigh_depth(nm):
    """SPECTRL2's Rayleigh optical depth at 1013.25 hPa (Bird and Riordan 1986, (2))."""
    um = nm / 1000.0
    return 1.0 / (um ** 4 * (115.6406 - 1.335 / um ** 2))


def compare():
    """Per sun elevation: atmo's direct transmittance and diffuse horizontal
    irradiance over SPECTRL2's, at each wavelength of 420-670 nm."""
    sky = atmo.Sky("earth-spectral")
    wl = sky.wavelengths_nm
    depth = sky.optical_depths()
    band = np.flatnonzero((wl >= 420) & (wl <= 670))

    def spectrl2(zenith, pressure, ozone):
        airmass = pvlib.atmosphere.get_relative_airmass(zenith, model="kastenyoung1989")
        out = pvlib.spectrum.spectrl2(
            apparent_zenith=zenith, aoi=0.0, surface_tilt=0.0, ground_albedo=0.1,
            surface_pressure=pressure, relative_airmass=airmass, precipitable_water=0.0,
            ozone=ozone, aerosol_turbidity_500nm=depth["aerosols"][0], dayofyear=93,
            alpha=0.0, wavelength_variation_factor=0.0, scattering_albedo_400nm=0.9,
            aerosol_asymmetry_factor=0.8)
        at = np.asarray(out["wavelength"]).ravel()
        return {k: np.interp(wl, at, np.asarray(out[k]).ravel())
                for k in ("dni", "dni_extra", "dhi")}

    # SPECTRL2's ozone depth per wavelength for 0.3 atm-cm, from the sun overhead.
    with_ozone, without = spectrl2(0.0, 101325.0, 0.3), spectrl2(0.0, 101325.0, 1e-9)
    ozone_airmass = 1.003454 / np.sqrt(1.0 + 0.006908)
    with np.errstate(divide="ignore", invalid="ignore"):  # dark ends of its spectrum
        ozone_depth = np.log(without["dni"] / with_ozone["dni"]) / ozone_airmass

    rows = []
    for elevation in ELEVATIONS:
        toward = [0.0, np.sin(np.radians(elevation)), np.cos(np.radians(elevation))]
        ours = sky.irradiance(sun_elevation=elevation, sun_azimuth=180.0,
                              normal=[toward, (0.0, 1.0, 0.0)])
        direct, diffuse = [], []
        for k in band:
            pressure = 101325.0 * depth["rayleigh"][k] / rayleigh_depth(wl[k])
            # Where SPECTRL2's ozone does not absorb (420-440 nm), atmo's depth is
            # under 0.0013: the column stays.
            ozone = 0.3 * depth["ozone"][k] / ozone_depth[k] if ozone_depth[k] > 1e-5 else 0.3
            theirs = spectrl2(90.0 - elevation, pressure, ozone)
            direct.append((ours.direct[0, k] / sky.solar_irradiance[k])
                          / (theirs["dni"][k] / theirs["dni_extra"][k]))
            diffuse.append(ours.diffuse[1, k] / theirs["dhi"][k])
        rows.append((elevation, np.array(direct), np.array(diffuse)))
    return rows


@pytest.fixture(scope="module")
def compared():
    return compare()


def test_the_direct_light_within_2_percent_at_420_to_670_nm(compared):
    for elevation, direct, _ in compared:
        assert np.max(np.abs(direct - 1.0)) < 0.02, (elevation, direct)


def test_the_diffuse_light_on_a_horizontal_surface_within_15_percent(compared):
    for elevation, _, diffuse in compared:
        assert np.max(np.abs(diffuse - 1.0)) < 0.15, (elevation, diffuse)


if __name__ == "__main__":
    # The figures of docs/python.md: python crates/atmo-py/tests/test_spectrl2.py
    print("sun deg | direct: min median max | diffuse: min median max (atmo / SPECTRL2)")
    for elevation, direct, diffuse in compare():
        print(f"{elevation:7.0f} | {direct.min():.4f} {np.median(direct):.4f} {direct.max():.4f}"
              f" | {diffuse.min():.3f} {np.median(diffuse):.3f} {diffuse.max():.3f}")
