#!/usr/bin/env bash
# One simulated hour replayed on the 20 000-dof deck (the bundled deck's
# control net refined to 100 × 40; `modes = "auto"` truncates at 160 Hz),
# 10-minute windows, six warm-started updates. The recording is simulated
# from the refined true deck (config/sinello-truth.toml at 100 × 40: random
# force at P1, 12 accelerometers at 256 Hz, seed 7), so the data fit the
# model. Prints the replay's own summary line (time and × real time) for
# RUNS runs and checks the results are byte-identical between runs.
# Needs a release build. Usage: benches/replay_large.sh [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${CARGO_TARGET_DIR:-target}/release/splinewatch
runs=${1:-3}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
sed "s/control_points = \[13, 5\]/control_points = [100, 40]/" config/sinello-truth.toml > "$work/truth.toml"
sed -e "s/control_points = \[13, 5\]/control_points = [100, 40]/" -e "s/^window_seconds = 20.0 .*/window_seconds = 600.0/" \
  config/sinello.toml > "$work/deck.toml"
"$bin" simulate --config "$work/truth.toml" --duration 3600 --seed 7 --out "$work/hour.mcap" 2> /dev/null
for run in $(seq 1 "$runs"); do
  "$bin" replay --config "$work/deck.toml" "$work/hour.mcap" --out "$work/results-$run.mcap" 2>&1 | grep '^replayed'
  cmp "$work/results-1.mcap" "$work/results-$run.mcap"
done
