"""Clouds through the Python package."""

import numpy as np
import pytest

import atmo


@pytest.fixture(scope="module")
def cloud():
    return atmo.clouds.cumulus(particles=3000, seed=7)


def test_a_cumulus_is_rows_of_particles(cloud):
    assert cloud.shape == (3000, 6) and cloud.dtype == np.float32
    assert np.all(cloud[:, 3] > 0) and np.all((cloud[:, 5] >= 0) & (cloud[:, 5] <= 1))
    assert cloud[:, 1].min() > 1000, "above its base, 1.5 km up"
    np.testing.assert_array_equal(cloud, atmo.clouds.cumulus(particles=3000, seed=7))


def test_a_cloud_before_the_sky_and_its_higher_orders(cloud):
    view = dict(width=96, height=54, resolution=64)
    single = atmo.clouds.render(cloud, scattering="single", **view)
    every = atmo.clouds.render(cloud, **view)  # the default: the transfer solve
    assert every.shape == (54, 96, 3) and every.dtype == np.float32
    assert np.all(np.isfinite(every)) and np.all(every >= 0)
    # The higher orders only add light; the sky fills the corners either way.
    assert every.mean() > single.mean()
    assert np.all(every >= single - 1e-3 * single.max())
    # The default is the solve; the table's every order within a fifth of it.
    solved = atmo.clouds.render(cloud, scattering="solve", **view)
    np.testing.assert_allclose(every, solved, rtol=1e-3, atol=1e-6 * solved.max())
    table = atmo.clouds.render(cloud, scattering="multiple", **view)
    assert np.all(np.isfinite(table)) and table.mean() > single.mean()
    assert abs(table.mean() / every.mean() - 1) < 0.2
    # Without the sky: black around the cloud, and the cloud lit by the sun alone.
    bare = atmo.clouds.render(cloud, sky=False, **view)
    assert np.all(bare[0, 0] == 0) and every[0, 0].sum() > 0
    assert 0 < bare.mean() < every.mean()


@pytest.mark.parametrize("particles, scattering, names", [
    (np.zeros((0, 6)), "single", "none"),
    (np.ones((4, 5)), "single", "six"),
    ([[0, 1500, 0, -1.0, 0.01, 0.9]], "single", "radius"),
    ([[0, 1500, 0, 10.0, 0.01, 1.5]], "single", "albedo"),
    ([[0, 1500, 0, 10.0, 0.01, 0.9]], "double", "scattering"),
])
def test_bad_particles_are_refused_naming_them(particles, scattering, names):
    with pytest.raises(ValueError, match=names):
        atmo.clouds.render(particles, scattering=scattering, width=8, height=8)


def test_particles_past_the_memory_budget_are_refused_before_they_are_made():
    # 6 million particles would hold about 3 GB: past the library's 2 GiB budget,
    # refused naming the count before the generator runs (it took the memory before).
    with pytest.raises(ValueError, match="6000000 particles.*memory budget"):
        atmo.clouds.cumulus(particles=6_000_000)
