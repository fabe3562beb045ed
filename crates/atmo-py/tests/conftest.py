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


@pytest.fixture(scope="session")
def tiny_table(tmp_path_factory):
    """A small skylight table of the default Earth, made by the atmo binary that
    `cargo test --workspace` built (a few seconds)."""
    import subprocess

    binary = next((p for p in (ROOT / "target" / d / "atmo" for d in ("debug", "release"))
                   if p.exists()), None)
    assert binary is not None, "the atmo binary: run `cargo build -p atmo-cli` first"
    path = tmp_path_factory.mktemp("table") / "tiny.atmo-sky"
    subprocess.run([str(binary), "precompute", "sky", "-o", str(path), "--sun-steps", "16",
                    "--altitude-steps", "2", "--max-altitude", "2000", "--directions", "32"],
                   check=True, capture_output=True)
    return path
