#!/usr/bin/env bash
# Benchmark (2) of issue 32: one simulated hour of output-only ambient data
# on the bundled ambient config (12 accelerations at 256 Hz, 4 random
# sources, seed 7) with 10-minute windows: per window SSI-cov with its
# jackknife, then an update on the identified modes (six, warm-started),
# replayed by the whole CLI, next to `cat` of the file; also in line
# (`--single-thread`) and a check that both write the same bytes.
# Needs a release build (`cargo build --release`). Usage:
# benches/replay_ambient_hour.sh [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${SPLINEWATCH_BIN:-${CARGO_TARGET_DIR:-target}/release/splinewatch}
runs=${1:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
sed "s/^window_seconds = 1200.0 .*/window_seconds = 600.0/" config/sinello-ambient.toml > "$work/ambient.toml"
grep -q "^window_seconds = 600.0" "$work/ambient.toml"
"$bin" simulate --config "$work/ambient.toml" --duration 3600 --seed 7 --excitation ambient --out "$work/hour.mcap" 2> /dev/null
seconds() { local t0 t1; t0=$(date +%s.%N); "$@" > /dev/null 2>&1; t1=$(date +%s.%N); echo "$t1 - $t0" | bc; }
cat "$work/hour.mcap" > /dev/null # in the page cache, as for every run below
echo "file: $(stat -c %s "$work/hour.mcap") bytes"
for run in $(seq 1 "$runs"); do
  cat_s=$(seconds cat "$work/hour.mcap")
  replay_s=$(seconds "$bin" replay --config "$work/ambient.toml" "$work/hour.mcap" --out "$work/results.mcap")
  inline_s=$(seconds "$bin" replay --config "$work/ambient.toml" "$work/hour.mcap" --out "$work/results-in-line.mcap" --single-thread)
  cmp "$work/results.mcap" "$work/results-in-line.mcap"
  printf 'run %d: cat %.3f s; replay %.3f s (%.0fx real time); in line %.3f s (%.0fx)\n' \
    "$run" "$cat_s" "$replay_s" "$(echo "3600 / $replay_s" | bc -l)" "$inline_s" "$(echo "3600 / $inline_s" | bc -l)"
done
