#!/usr/bin/env bash
# Every test of atmo: the Rust workspace's (arguments go to `cargo test`), then the
# Python package's: built by pip into a virtual environment under target/, with
# pytest, pvlib and pandas from PyPI, and run by pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo test --workspace "$@"
venv=target/python-venv
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
"$venv/bin/python" -m pip install -q --upgrade pip
"$venv/bin/python" -m pip install -q "./crates/atmo-py[test]"
"$venv/bin/python" -m pytest -q crates/atmo-py/tests
