#!/usr/bin/env bash
# Runs the fuzz targets (all, or those named after SECONDS) for SECONDS each from their
# seed corpora (corpus/TARGET, the project's own files), with a 256 MiB budget inside
# and libFuzzer's limits outside: any single allocation of 512 MB or more, or 2 GB
# resident, is a failure. New inputs go to work/TARGET (not committed); crashes to
# artifacts/TARGET. Needs the nightly toolchain and cargo-fuzz (installed if missing).
set -euo pipefail
cd "$(dirname "$0")"
seconds=${1:-60}
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=(atmosphere_toml scene_toml sky_table particles obj gobo probe_csv)
fi
command -v cargo-fuzz >/dev/null 2>&1 || cargo install cargo-fuzz --locked --version 0.13.2
cargo +nightly fuzz build 2>&1 | tail -n 3
for target in "${targets[@]}"; do
  mkdir -p "work/$target"
  echo "== fuzz $target for ${seconds}s"
  cargo +nightly fuzz run "$target" "work/$target" "corpus/$target" -- \
    -max_total_time="$seconds" -rss_limit_mb=2048 -malloc_limit_mb=512 -print_final_stats=1 \
    2>&1 | grep -E "(DONE|stat::number_of_executed_units|stat::peak_rss_mb|^==|SUMMARY|panicked|INFO: seed corpus)" || true
  # A crash leaves its input in artifacts/ and a non-zero status in the log above.
  if compgen -G "artifacts/$target/*" >/dev/null; then
    echo "fuzz $target: found a failing input: $(ls artifacts/"$target")" >&2
    exit 1
  fi
done
