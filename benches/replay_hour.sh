#!/usr/bin/env bash
# Benchmark (1) of issue 17: one simulated hour of the bundled deck (13
# channels at 256 Hz: the force at P1 and 12 accelerations, seed 7, 94 MB of
# MCAP), 10-minute windows, an update per window (six, warm-started),
# replayed by the whole CLI, next to the I/O floor of the same file: `cat`
# of it to /dev/null, and zstd decompressing the same bytes (compressed at
# level 3 beforehand, not timed). Also the replay in line
# (`--single-thread`), and a check that both write the same bytes.
# Needs a release build (`cargo build --release`). Usage:
# benches/replay_hour.sh [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${SPLINEWATCH_BIN:-${CARGO_TARGET_DIR:-target}/release/splinewatch}
runs=${1:-5}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
sed "s/^window_seconds = 20.0 .*/window_seconds = 600.0/" config/sinello.toml > "$work/hour.toml"
"$bin" simulate --config "$work/hour.toml" --duration 3600 --seed 7 --out "$work/hour.mcap" 2> /dev/null
zstd -q -3 "$work/hour.mcap" -o "$work/hour.mcap.zst"
seconds() { local t0 t1; t0=$(date +%s.%N); "$@" > /dev/null 2>&1; t1=$(date +%s.%N); echo "$t1 - $t0" | bc; }
cat "$work/hour.mcap" > /dev/null # in the page cache, as for every run below
echo "file: $(stat -c %s "$work/hour.mcap") bytes"
for run in $(seq 1 "$runs"); do
  cat_s=$(seconds cat "$work/hour.mcap")
  zstd_s=$(seconds zstd -d -c "$work/hour.mcap.zst")
  replay_s=$(seconds "$bin" replay --config "$work/hour.toml" "$work/hour.mcap" --out "$work/results.mcap")
  inline_s=$(seconds "$bin" replay --config "$work/hour.toml" "$work/hour.mcap" --out "$work/results-in-line.mcap" --single-thread)
  cmp "$work/results.mcap" "$work/results-in-line.mcap"
  printf 'run %d: cat %.3f s, zstd -d %.3f s; replay %.3f s (%.0fx real time, %.1fx the cat + zstd floor); in line %.3f s\n' \
    "$run" "$cat_s" "$zstd_s" "$replay_s" "$(echo "3600 / $replay_s" | bc -l)" \
    "$(echo "$replay_s / ($cat_s + $zstd_s)" | bc -l)" "$inline_s"
done
