"""The Python package's radiance, vectorised, against the same work through the CLI.

10,000 directions (a grid of 100 azimuths x 100 elevations over the upper hemisphere)
for 100 suns (1 to 89 deg), every order of the default Earth at sea level:

- python.radiance: one `Sky.radiance` call in a process that has made the model
  (the model's first computation is timed apart, as python.cold);
- python.table: the same through a skylight table (`--table`, from `atmo precompute
  sky`), linear sRGB; the CLI cannot probe a table, so its baseline is the same;
- their baseline: `atmo sky --probe DIRS.csv --sun-elevation S` once per sun, a process
  each, as a program had to before the package. The CLI is timed on `--cli-suns` of
  the suns (10 unless given) and scaled to 100, since each call takes seconds.

Prints one JSON line per case in `atmo bench --json`'s format, for docs/bench:

    atmo precompute sky -o earth.atmo-sky
    python crates/atmo-py/bench/radiance.py --atmo target/release/atmo \
        --table earth.atmo-sky > docs/bench/python.json
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

import atmo

COMMAND = ("python crates/atmo-py/bench/radiance.py --atmo target/release/atmo "
           "--table earth.atmo-sky")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--atmo", required=True, help="the atmo binary")
    parser.add_argument("--cli-suns", type=int, default=10)
    parser.add_argument("--table", help="a skylight table (atmo precompute sky)")
    args = parser.parse_args()

    az = np.linspace(0.0, 360.0, 100, endpoint=False)
    el = np.linspace(0.45, 89.55, 100)
    suns = np.linspace(1.0, 89.0, 100)
    sky = atmo.Sky("earth")

    start = time.perf_counter()
    sky.radiance(sun_elevation=30.0, azimuth=0.0, elevation=45.0)
    cold_ms = 1e3 * (time.perf_counter() - start)

    start = time.perf_counter()
    L = sky.radiance(sun_elevation=suns[:, None, None], azimuth=az[None, None, :],
                     elevation=el[None, :, None])
    python_ms = 1e3 * (time.perf_counter() - start)

    table_ms = None
    if args.table:
        table = atmo.SkyTable(args.table)
        start = time.perf_counter()
        rgb = table.radiance(sun_elevation=suns[:, None, None], azimuth=az[None, None, :],
                             elevation=el[None, :, None])
        table_ms = 1e3 * (time.perf_counter() - start)
        assert rgb.shape == L.shape[:-1] + (3,)

    with tempfile.TemporaryDirectory() as folder:
        dirs = os.path.join(folder, "dirs.csv")
        with open(dirs, "w") as f:
            f.write("azimuth_deg,elevation_deg\n")
            for e in el:
                for a in az:
                    f.write(f"{a - 180.0},{e}\n")  # from the sun's azimuth (180)
        picked = np.linspace(0, len(suns) - 1, args.cli_suns).round().astype(int)
        start = time.perf_counter()
        worst = 0.0
        for k in picked:
            out = subprocess.run(
                [args.atmo, "sky", "--probe", dirs, "--sun-elevation", str(suns[k])],
                check=True, capture_output=True, text=True).stdout
            cli = np.loadtxt(out.splitlines()[1:], delimiter=",")[:, 2:]
            ours = L[k].reshape(-1, L.shape[-1])
            worst = max(worst, float(np.max(np.abs(ours / cli - 1.0))))
        cli_ms = 1e3 * (time.perf_counter() - start) * len(suns) / len(picked)

    params = {"directions": az.size * el.size, "suns": suns.size, "order": "all",
              "altitude_m": 0.0, "wavelengths": int(L.shape[-1])}
    for line in [
        {"bench": "python.radiance", "command": COMMAND, "params": params,
         "median_ms": python_ms,
         "baseline": f"atmo sky --probe, a process a sun ({args.cli_suns} timed, scaled)",
         "baseline_median_ms": cli_ms, "ratio": cli_ms / python_ms,
         "error": {"max_relative_to_cli": worst}},
        {"bench": "python.cold", "command": COMMAND, "params": params,
         "median_ms": cold_ms},
    ] + ([] if table_ms is None else [
        {"bench": "python.table", "command": COMMAND,
         "params": dict(params, wavelengths=3, order="the table's"),
         "median_ms": table_ms,
         "baseline": f"atmo sky --probe, a process a sun ({args.cli_suns} timed, scaled)",
         "baseline_median_ms": cli_ms, "ratio": cli_ms / table_ms},
    ]):
        print(json.dumps(line, sort_keys=True))


if __name__ == "__main__":
    sys.exit(main())
