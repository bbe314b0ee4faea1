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
. benches/replay_runs.sh
replay_runs "$bin" "$work/ambient.toml" "$work/hour.mcap" "$work" "$runs"
