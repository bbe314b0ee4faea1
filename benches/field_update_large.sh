#!/usr/bin/env bash
# Stiffness fields at scale: the bundled deck refined to 100 × 40 control
# points (20 000 dofs, `modes = "auto"` truncates at 160 Hz) with eight
# stiffness regions (ξ in quarters, η in halves, degree 0), region 6 30 %
# softer in the true deck; accelerances P1 → P1…P12, 1–80 Hz every 0.25 Hz,
# 1 % noise. One `splinewatch update` of the 8 springs, the 8 θ and the 7
# damping coefficients from the config's start: prints the identified
# parameters, the wall time and the peak RSS (/usr/bin/time).
# Needs a release build. Usage: benches/field_update_large.sh
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${CARGO_TARGET_DIR:-target}/release/splinewatch
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
field='
[[model.stiffness_fields]]
name = "deck"
knots_xi = [0.0, 0.25, 0.5, 0.75, 1.0]
degree_xi = 0
knots_eta = [0.0, 0.5, 1.0]
degree_eta = 0
bounds = [0.3, 1.5]'
refine='s/control_points = \[13, 5\]/control_points = [100, 40]/'
{ sed "$refine" config/sinello-truth.toml; echo "$field"; echo 'coefficients = [1.0, 1.0, 1.0, 1.0, 1.0, 0.7, 1.0, 1.0]'; } > "$work/truth.toml"
{ sed "$refine" config/sinello.toml; echo "$field"; } > "$work/deck.toml"
"$bin" synth --config "$work/truth.toml" --inputs P1 --outputs P1,P2,P3,P4,P5,P6,P7,P8,P9,P10,P11,P12 \
  --from 1 --to 80 --step 0.25 --noise 0.01 --seed 3 --out "$work/frf.json" > /dev/null 2>&1
/usr/bin/time -f 'one update: %e s wall, peak RSS %M KB' "$bin" update --config "$work/deck.toml" --frf "$work/frf.json" 2>&1 \
  | grep -E '^(deck|west|east)\.|^converged|^modal truncation|^one update'
