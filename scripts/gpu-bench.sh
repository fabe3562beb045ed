#!/usr/bin/env bash
# The GPU benchmarks on a machine with a hardware GPU and its Vulkan driver, unattended:
# builds in release, runs `atmo bench AREA --backend gpu --json --quick` for the sky, the
# table, the shafts and the clouds, and the Bevy comparison (bevy_atmo against the same
# scene without a sky and against Bevy's own Atmosphere), each case a JSON line, into
# the folder given (one file an area, as docs/bench/ names them). Under 8 minutes on a
# 16-core machine: the build takes most of it.
#
#   scripts/gpu-bench.sh OUT_FOLDER
#
# Copy the files into docs/bench/ (with a line in docs/bench/machine.txt naming the
# GPU) and run `atmo bench page -o docs/benchmarks.md`.
set -euo pipefail
cd "$(dirname "$0")/.."
out=${1:?usage: scripts/gpu-bench.sh OUT_FOLDER}
mkdir -p "$out"
export NODEVICE_SELECT=1

echo "== build (release)"
cargo build --release -p atmo-cli -p bevy_atmo --example bench 2>&1 | tail -n 1
atmo=target/release/atmo

# Each area to a temporary file, renamed when whole: an area that fails leaves no file.
run() {
  local name=$1; shift
  echo "== $name: $*"
  if "$@" > "$out/$name.json.tmp"; then
    mv "$out/$name.json.tmp" "$out/$name.json"
  else
    echo "   failed (exit $?): $out/$name.json not written" >&2
    rm -f "$out/$name.json.tmp"
  fi
}
for area in sky sky-table shafts clouds; do
  run "$area-gpu" timeout 120 "$atmo" bench "$area" --backend gpu --json --quick
done
run bevy timeout 120 target/release/examples/bench --json
ls -l "$out"
