#!/usr/bin/env bash
# Predicts every Painter Street record in DIR (the station zips of CSMIP
# station 89324, e.g. github chrystalchern/mdof notebooks/uploads/CE89324)
# with config/painter-street.toml at its values, and prints per event the
# median NRMSE over the strong motion of the transverse deck channels (7, 9,
# 4) and of every deck channel, beside the "deck = nearest ground" baseline.
# Usage: benches/painter_street_predict.sh DIR [splinewatch binary]
set -euo pipefail
dir="$1"
bin="${2:-target/release/splinewatch}"
printf "%-52s %-20s %8s %8s %8s %8s %8s\n" event start pga_m/s2 tr_model tr_base all_model all_base
for zip in "$dir"/*.zip; do
  json=$("$bin" predict --config config/painter-street.toml "$zip" --json 2>/dev/null) || { echo "$(basename "$zip"): failed"; continue; }
  python3 - "$zip" "$json" <<'PY'
import json, os, statistics, sys
zip_path, text = sys.argv[1], sys.argv[2]
d = json.loads(text)
model = {c["sensor"]: c["nrmse_strong"] for c in d["channels"]}
base = {c["sensor"]: c["nrmse_strong"] for c in d["baseline"]}
tr = [s for s in ("ch7", "ch9", "ch4") if s in model]
med = lambda xs: statistics.median(xs) if xs else float("nan")
print(f"{os.path.basename(zip_path):52s} {(d.get('start') or '?')[:19]:20s} {d.get('pga_ground', float('nan')):8.3f} {med([model[s] for s in tr]):8.3f} {med([base[s] for s in tr]):8.3f} {med(list(model.values())):8.3f} {med(list(base.values())):8.3f}")
PY
done
