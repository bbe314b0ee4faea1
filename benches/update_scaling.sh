#!/usr/bin/env bash
# One whole update at 325 / 3 200 / 20 000 / 80 000 dofs: the bundled deck's
# control net refined (config/sinello.toml, `[model.solver] modes = "auto"`:
# every mode up to 2 000 dofs, the modes below 160 Hz plus the residual
# above), updated from the config's start values against synthetic
# accelerances (1 % noise, P1 → the 12 sensors, 0.5–80 Hz every 0.25 Hz) of
# the same net with the true springs (config/sinello-truth.toml), so the
# data fit the model. Reports the CLI's wall time (assembly included),
# the iterations and model evaluations, and peak RSS from /usr/bin/time.
# Needs a release build. Usage: benches/update_scaling.sh [NETS...]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${CARGO_TARGET_DIR:-target}/release/splinewatch
nets=("${@:-13,5 40,16 100,40}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
printf '| net | dofs | modes | one whole update | iterations (evaluations) | peak RSS |\n'
printf '| --- | --- | --- | --- | --- | --- |\n'
for net in ${nets[*]}; do
  m=${net%,*}; n=${net#*,}
  for c in sinello sinello-truth; do
    sed "s/control_points = \[13, 5\]/control_points = [$m, $n]/" "config/$c.toml" > "$work/$c-$m-$n.toml"
  done
  "$bin" synth --config "$work/sinello-truth-$m-$n.toml" --inputs P1 \
    --outputs P1,P2,P3,P4,P5,P6,P7,P8,P9,P10,P11,P12 --from 0.5 --to 80 --step 0.25 --noise 0.01 \
    --out "$work/frf.json" 2> /dev/null
  start=$(date +%s.%N)
  /usr/bin/time -f '%M' -o "$work/rss" "$bin" update --config "$work/sinello-$m-$n.toml" --frf "$work/frf.json" \
    > "$work/out" 2> "$work/err"
  end=$(date +%s.%N)
  seconds=$(echo "$end - $start" | bc)
  summary=$(grep '^converged' "$work/out")
  iterations=$(sed -E 's/.* after ([0-9]+) iterations, ([0-9]+) model evaluations.*/\1 (\2)/' <<< "$summary")
  modes=$(grep -o 'modal truncation: [0-9]* modes below [0-9.]* Hz' "$work/err" | sed -E 's/modal truncation: //' || true)
  printf '| %s × %s | %s | %s | %.2f s | %s | %s MB |\n' "$m" "$n" "$((m * n * 5))" "${modes:-all}" "$seconds" \
    "$iterations" "$(( $(cat "$work/rss") / 1024 ))"
done
