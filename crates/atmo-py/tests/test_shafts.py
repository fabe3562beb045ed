"""Light shafts through the Python package."""

import numpy as np
import pytest

import atmo


def test_a_scene_file_renders_to_radiance(scenes):
    img = atmo.shafts.render(scenes / "spotlight-sphere.toml")
    assert img.shape == (480, 720, 3) and img.dtype == np.float32
    assert np.all(np.isfinite(img)) and np.all(img >= 0) and img.max() > 0


def test_the_show_moves_with_time_and_bad_files_are_refused(scenes, tmp_path):
    start = atmo.shafts.render(scenes / "show.toml", time=0.0)
    later = atmo.shafts.render(scenes / "show.toml", time=3.0)
    assert np.abs(start - later).mean() > 1e-3 * start.mean()
    bad = tmp_path / "bad.toml"
    bad.write_text((scenes / "spotlight-sphere.toml").read_text().replace(
        "fov_deg = 50.0", "fov_deg = 500.0"))
    with pytest.raises(ValueError, match="fov_deg"):
        atmo.shafts.render(bad)
