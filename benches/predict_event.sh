#!/usr/bin/env bash
# Issue 44's speed target: import + predict of one earthquake record, whole
# CLI. Times `predict` (five runs each) on
#  1. the real 28 Jan 2015 Painter Street record as the CESMD zips it
#     (17 channels: 9 ground, 8 deck; 85.1 s at 100 Hz);
#  2. a 28-channel record of the same event: config/painter-street.toml with
#     11 more deck accelerometers, simulated from the record's ground
#     channels (`simulate --ground`, 2 % noise), read back from MCAP;
# and, for scale, the same with every mode (the dense path).
# Usage: benches/predict_event.sh [splinewatch binary]
set -euo pipefail
bin="${1:-target/release/splinewatch}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
zip=tests/fixtures/painter-street/ferndale_28jan2015_72387946_ce89324p.zip
cp config/painter-street.toml "$tmp/28.toml"
for k in $(seq 1 11); do
  x=$(python3 -c "print(round(3.0 + 6.9 * $k, 2))")
  dir=$([ $((k % 2)) -eq 0 ] && echo y || echo z)
  printf '\n[[sensors]]\nname = "extra%d"\nx = %s\ny = 0.0\nz = 0.0\ndirection = "%s"\n' "$k" "$x" "$dir" >> "$tmp/28.toml"
done
"$bin" simulate --config "$tmp/28.toml" --ground "$zip" --noise 0.02 --out "$tmp/28.mcap" 2>/dev/null
sed 's/^modes = "truncated"/modes = "all"/' config/painter-street.toml > "$tmp/dense.toml"
time_runs() {
  local label="$1"; shift
  local times=()
  for _ in 1 2 3 4 5; do
    local start end
    start=$(date +%s.%N)
    "$bin" predict "$@" > /dev/null 2>&1
    end=$(date +%s.%N)
    times+=("$(python3 -c "print(f'{$end - $start:.3f}')")")
  done
  echo "$label: ${times[*]} s"
}
time_runs "17 channels, CESMD zip, modes below 50 Hz" --config config/painter-street.toml "$zip"
time_runs "28 channels, MCAP, modes below 50 Hz" --config "$tmp/28.toml" "$tmp/28.mcap"
time_runs "17 channels, CESMD zip, every mode" --config "$tmp/dense.toml" "$zip"
