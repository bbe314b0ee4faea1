#!/usr/bin/env bash
# Benchmark (3) of issue 32: the monitoring workload. One simulated hour of
# the bundled deck (13 channels at 256 Hz, seed 7) with a bearing losing
# stiffness mid-way (`east.k2` down 40 % between minutes 24 and 36, the
# demo's scenario), 10-minute windows and 8-s Welch segments (0.125 Hz
# lines, what decks need): six warm-started FRF updates, replayed by the
# whole CLI next to `cat` of the file; also in line (`--single-thread`) and
# a check that both write the same bytes.
# Needs a release build (`cargo build --release`). Usage:
# benches/replay_bearing_hour.sh [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${SPLINEWATCH_BIN:-${CARGO_TARGET_DIR:-target}/release/splinewatch}
runs=${1:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
sed -e "s/^window_seconds = 20.0 .*/window_seconds = 600.0/" \
  -e "s/^segment_seconds = 4.0.*/segment_seconds = 8.0/" config/sinello.toml > "$work/hour.toml"
grep -q "^window_seconds = 600.0" "$work/hour.toml"
grep -q "^segment_seconds = 8.0" "$work/hour.toml"
cat > "$work/bearing.toml" << 'SCENARIO'
[[change]]
parameter = "east.k2"
start_minute = 24.0
end_minute = 36.0
factor = 0.6
SCENARIO
"$bin" simulate --config "$work/hour.toml" --duration 3600 --seed 7 --scenario "$work/bearing.toml" \
  --out "$work/hour.mcap" 2> /dev/null
. benches/replay_runs.sh
replay_runs "$bin" "$work/hour.toml" "$work/hour.mcap" "$work" "$runs"
