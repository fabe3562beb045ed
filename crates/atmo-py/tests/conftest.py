import pathlib

import pytest

import atmo

ROOT = pathlib.Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def sky():
    """The default sky (every order, ozone), made once: its models are kept."""
    return atmo.Sky("earth")


@pytest.fixture(scope="session")
def scenes():
    return ROOT / "scenes"
