"""The sun's position against pvlib's SPA, which no one here wrote."""

import numpy as np
import pandas as pd
import pytest

import atmo

pvlib = pytest.importorskip("pvlib")


@pytest.mark.parametrize("latitude, longitude, altitude", [
    (48.85, 2.35, 35.0),       # Paris
    (-33.92, 18.42, 10.0),     # Cape Town
    (64.84, -147.72, 136.0),   # Fairbanks: the sun low for months
])
def test_a_year_of_hours_within_a_thousandth_of_a_degree_of_pvlib(latitude, longitude, altitude):
    times = pd.date_range("2026-01-01", "2027-01-01", freq="1h", tz="UTC", inclusive="left")
    ours = atmo.sun_position(latitude, longitude, times, altitude=altitude)
    theirs = pvlib.solarposition.get_solarposition(
        times, latitude, longitude, altitude=altitude, method="nrel_numpy")
    assert ours.elevation.shape == (len(times),)
    np.testing.assert_allclose(ours.elevation, theirs["elevation"].to_numpy(), atol=1e-3)
    # Azimuth where it is defined (not within a hair of the zenith), across 0/360.
    d = (ours.azimuth - theirs["azimuth"].to_numpy() + 180.0) % 360.0 - 180.0
    assert np.max(np.abs(d[ours.elevation < 89.9])) < 1e-3


def test_times_as_numpy_or_datetime_agree_and_bad_times_are_refused():
    import datetime as dt
    when = dt.datetime(2026, 6, 21, 10, 30, tzinfo=dt.timezone(dt.timedelta(hours=2)))
    a = atmo.sun_position(48.85, 2.35, [when])
    b = atmo.sun_position(48.85, 2.35, np.array(["2026-06-21T08:30"], dtype="datetime64[s]"))
    np.testing.assert_array_equal(a.elevation, b.elevation)
    assert a.apparent_elevation[0] > a.elevation[0] > 40
    with pytest.raises(ValueError, match="latitude"):
        atmo.sun_position(95, 0, [when])
    with pytest.raises(ValueError, match="times"):
        atmo.sun_position(0, 0, [1.5, 2.5])
