"""The sky through the Python package: shapes, broadcasting, physics and errors."""

import numpy as np
import pytest

import atmo


def test_the_spectral_preset_spans_the_visible_in_40_or_more_wavelengths():
    sky = atmo.Sky("earth-spectral", order=1)
    wl = sky.wavelengths_nm
    assert len(wl) >= 40 and wl[0] <= 360 and wl[-1] >= 830
    assert "earth" in atmo.presets() and sky.order == "1"


def test_radiance_broadcasts_and_is_positive_and_finite(sky):
    az = np.linspace(0, 360, 7)[None, :]
    el = np.array([-20.0, 0.5, 10.0, 45.0, 90.0])[:, None]
    L = sky.radiance(sun_elevation=20, azimuth=az, elevation=el)
    assert L.shape == (5, 7, 6) and L.dtype == np.float32
    assert np.all(np.isfinite(L)) and np.all(L > 0)
    # Many suns at once, the same as one at a time.
    suns = np.array([2.0, 10.0, 30.0])
    many = sky.radiance(sun_elevation=suns[:, None], azimuth=200.0, elevation=el[:, 0])
    for k, s in enumerate(suns):
        one = sky.radiance(sun_elevation=s, azimuth=200.0, elevation=el[:, 0])
        np.testing.assert_array_equal(many[k], one)


def test_the_sky_is_symmetric_about_the_suns_vertical_plane(sky):
    offsets = np.array([10.0, 60.0, 150.0])
    left = sky.radiance(sun_elevation=15, sun_azimuth=120, azimuth=120 - offsets, elevation=20)
    right = sky.radiance(sun_elevation=15, sun_azimuth=120, azimuth=120 + offsets, elevation=20)
    np.testing.assert_allclose(left, right, rtol=1e-6)
    # And brighter toward the sun than away from it, at every wavelength.
    assert np.all(left[0] > left[2])


def test_blue_sky_at_noon_and_red_light_at_sunset(sky):
    zenith = sky.radiance(sun_elevation=60, azimuth=0, elevation=90)
    assert zenith[0] > 2 * zenith[-1], "Rayleigh: 420 nm well above 670 nm"
    toward = sky.radiance(sun_elevation=1, azimuth=180, elevation=1)
    assert toward[-1] > toward[0], "the horizon under a setting sun is red"


def test_the_diffuse_irradiance_is_the_radiance_integrated_over_the_hemisphere(sky):
    """An independent quadrature written here (the midpoint rule over a fine
    latitude-longitude grid of the radiance) holds the package's double-Gauss rule."""
    el_edges = np.linspace(0, 90, 181)
    az_edges = np.linspace(0, 360, 361)
    el = np.radians(0.5 * (el_edges[1:] + el_edges[:-1]))
    az = 0.5 * (az_edges[1:] + az_edges[:-1])
    for sun in (5.0, 35.0):
        L = sky.radiance(sun_elevation=sun, azimuth=az[None, :],
                         elevation=np.degrees(el)[:, None])
        weight = (np.sin(el) * np.cos(el) * np.radians(0.5) * np.radians(1.0))[:, None, None]
        want = (L * weight).sum(axis=(0, 1))
        got = sky.irradiance(sun_elevation=sun).diffuse
        np.testing.assert_allclose(got, want, rtol=1e-3)


def test_direct_light_falls_by_the_cosine_and_global_adds_up(sky):
    sun, azimuth = 30.0, 200.0
    toward = np.array([np.sin(np.radians(azimuth)) * np.cos(np.radians(sun)),
                       np.sin(np.radians(sun)),
                       -np.cos(np.radians(azimuth)) * np.cos(np.radians(sun))])
    normals = np.stack([toward, [0.0, 1.0, 0.0], -toward])
    E = sky.irradiance(sun_elevation=sun, sun_azimuth=azimuth, normal=normals)
    assert E.direct.shape == (3, 6) and E.direct_lux.shape == (3,)
    np.testing.assert_allclose(E.direct[1], E.direct[0] * np.sin(np.radians(sun)), rtol=1e-6)
    assert np.all(E.direct[2] == 0), "a surface facing away gets no direct light"
    assert np.all(E.diffuse > 0)
    np.testing.assert_allclose(E.global_, E.direct + E.diffuse)
    # Clear-sky daylight at sun 30 deg: tens of kilolux direct, about ten diffuse.
    assert 30_000 < E.direct_lux[1] < 80_000, E.direct_lux
    assert 5_000 < E.diffuse_lux[1] < 25_000, E.diffuse_lux


def test_a_picture_of_the_sky(sky):
    rgb = sky.render(sun_elevation=5, width=64, height=36, fov=60)
    assert rgb.shape == (36, 64, 3) and rgb.dtype == np.float32
    assert np.all(np.isfinite(rgb)) and np.all(rgb >= 0)
    # Looking at the sun's azimuth: the picture is its own mirror image.
    np.testing.assert_allclose(rgb, rgb[:, ::-1], rtol=1e-3, atol=1e-6)


@pytest.mark.parametrize("call, names", [
    (lambda s: s.radiance(sun_elevation=95, azimuth=0, elevation=10), "sun_elevation"),
    (lambda s: s.radiance(sun_elevation=10, azimuth=0, elevation=-91), "elevation"),
    (lambda s: s.radiance(sun_elevation=10, azimuth=0, elevation=10, altitude=-5),
     "altitude"),
    (lambda s: s.irradiance(sun_elevation=10, normal=(0, 0, 0)), "normal"),
    (lambda s: s.irradiance(sun_elevation=10, normal=(0, 1)), "normal"),
    (lambda s: s.render(sun_elevation=10, width=0), "width"),
    (lambda s: atmo.Sky("mars"), "mars"),
    (lambda s: atmo.Sky("earth", order="many"), "order"),
])
def test_bad_arguments_raise_value_errors_naming_them(sky, call, names):
    with pytest.raises(ValueError, match=names):
        call(sky)


def test_a_table_draws_the_sky_of_its_model(sky, tiny_table):
    """The table (a small one: 16 suns, 2 altitudes, 32 directions) against the model
    it was computed from, in the same pictures of the sky above the horizon (the table
    holds no ground)."""
    table = atmo.Sky.from_table(tiny_table)
    assert table.name == "earth" and table.altitude_range == (0.0, 2000.0)
    for sun in (3.0, 25.0):
        view = dict(sun_elevation=sun, width=96, height=54, view_elevation=40, sun_disc=False)
        want, got = sky.render(**view), table.render(**view)
        assert abs(got.mean() / want.mean() - 1) < 0.02
        assert np.sqrt(np.mean((got - want) ** 2)) < 0.05 * want.mean()
    # Radiance: RGB, broadcast as the model's; no sky below the horizon.
    rgb = table.radiance(sun_elevation=[5.0, 40.0], azimuth=90.0, elevation=[[20.0], [-5.0]])
    assert rgb.shape == (2, 2, 3) and np.all(rgb[0] > 0) and np.all(rgb[1] == 0)
    with pytest.raises(ValueError, match="altitude"):
        table.radiance(sun_elevation=5.0, azimuth=0.0, elevation=10.0, altitude=5000.0)
