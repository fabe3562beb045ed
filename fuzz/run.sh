#!/usr/bin/env bash
# Runs the fuzz targets (all, or those named after SECONDS) for SECONDS each from their
# seed corpora (corpus/TARGET, the project's own files), JOBS at a time (default 2, one
# a core), with a 256 MiB budget inside and libFuzzer's limits outside, at the budget:
# inputs up to MAX_LEN bytes (default 4 MiB, so that memory defects of large inputs
# are reached; LEN_CONTROL=0 lets them grow there at once instead of gradually), any
# single allocation of 256 MiB or more, or a resident size past the budget plus the
# target's fixed footprint under AddressSanitizer (RSS_MB, default 416: 256 + its
# shadow + about 100 measured), is a failure. New inputs go to work/TARGET (not committed); a failing input to
# artifacts/TARGET, and the run fails.
# FUZZ_SEED fixes libFuzzer's random seed (CI: 1, so a run repeats its mutations;
# unset: a new seed each run). Needs the nightly toolchain and cargo-fuzz (installed if
# missing).
set -euo pipefail
cd "$(dirname "$0")"
seconds=${1:-60}
shift || true
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=(atmosphere_toml scene_toml sky_table particles obj gobo probe_csv photometry gdtf
    set_edits exr view_script cli_args cloud_scene table_part frames dmx mvr)
fi
command -v cargo-fuzz >/dev/null 2>&1 || cargo install cargo-fuzz --locked --version 0.13.2
cargo +nightly fuzz build 2>&1 | tail -n 1

fuzz_one() {
  target=$1
  mkdir -p "work/$target" "artifacts/$target"
  log="work/$target.log"
  # A small quarantine: freed memory AddressSanitizer holds back counts as resident.
  ASAN_OPTIONS=quarantine_size_mb=16:${ASAN_OPTIONS:-} \
    cargo +nightly fuzz run "$target" "work/$target" "corpus/$target" -- \
    -max_total_time="$seconds" -max_len="${MAX_LEN:-4194304}" -len_control="${LEN_CONTROL:-100}" \
    -rss_limit_mb="${RSS_MB:-416}" -malloc_limit_mb=256 -seed="${FUZZ_SEED:-0}" -print_final_stats=1 >"$log" 2>&1 || true
  # The closing lines: executions, coverage, corpus, peak memory, any failure.
  echo "== $target ($seconds s): $(grep -E "DONE|SUMMARY|panicked" "$log" | tail -n 2 | tr -s ' \t' ' ')"
  grep -E "stat::(number_of_executed_units|peak_rss_mb)" "$log" | tr -s ' ' | sed 's/^/   /'
}
export -f fuzz_one
export seconds
printf '%s\n' "${targets[@]}" | xargs -P "${JOBS:-2}" -I{} bash -c 'fuzz_one {}'
failed=0
for target in "${targets[@]}"; do
  if compgen -G "artifacts/$target/*" >/dev/null; then
    echo "fuzz $target: failing input $(ls "artifacts/$target"); log: fuzz/work/$target.log" >&2
    failed=1
  fi
done
exit $failed
