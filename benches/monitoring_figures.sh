#!/usr/bin/env bash
# The monitoring figures of the guide (tutorials/alarms.md): the two-week scenario
# (config/scenarios/two-weeks-bearing-loss.toml, 336 hourly windows,
# training on the first 100, damage from window 200) for three sizes of
# bearing loss, scored with temperature compensation (held-out limits),
# on raw parameters with the textbook F limits, and on raw parameters with
# held-out limits. Usage: benches/monitoring_figures.sh [splinewatch binary] [factors...]
set -euo pipefail
bin=${1:-target/release/splinewatch}
shift || true
factors=${*:-0.8 0.98 0.995}
cfg=config/sinello-monitoring.toml
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for factor in $factors; do
    sed "s/^factor = .*/factor = $factor/" config/scenarios/two-weeks-bearing-loss.toml > "$work/scenario.toml"
    "$bin" simulate --config "$cfg" --scenario "$work/scenario.toml" --frf-windows 336 --out "$work/frf.mcap" 2>/dev/null
    start=$(date +%s.%N)
    "$bin" replay --config "$cfg" "$work/frf.mcap" --out "$work/results.mcap" >/dev/null 2>&1
    end=$(date +%s.%N)
    echo "## east.k2 × $factor (replay of 336 windows: $(echo "$end - $start" | bc) s)"
    for mode in "" "--raw --limits theoretical" "--raw"; do
        echo "# monitor ${mode:-(compensated)}"
        "$bin" monitor --config "$cfg" "$work/results.mcap" --onset-window 200 $mode 2>&1
    done
done
