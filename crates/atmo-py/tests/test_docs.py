"""The Python written in README.md and docs/python.md runs as it stands."""

import re

import numpy as np
import pytest

from conftest import ROOT


def blocks(path):
    return re.findall(r"```python\n(.*?)```", path.read_text(), re.S)


@pytest.mark.parametrize("page", ["README.md", "docs/python.md"])
def test_the_python_in_the_docs_runs(page, tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT)
    found = blocks(ROOT / page)
    assert found, f"{page} has Python blocks"
    names = {"OUT": tmp_path}
    for code in found:
        exec(compile(code, page, "exec"), names)
    if page == "README.md":
        assert names["L"].shape == (3, 72, 48) and np.all(names["L"] > 0)
