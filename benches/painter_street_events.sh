#!/usr/bin/env bash
# Runs every Painter Street record in DIR (the station zips of CSMIP station
# 89324, e.g. github chrystalchern/mdof notebooks/uploads/CE89324) through
# one `splinewatch events` run with config/painter-street.toml (or $CONFIG), and prints per
# event the ground's peak, the identified modes, the updated lateral
# stiffnesses of the three support lines, the updated model's dominant mode,
# the update's fit and the forecast's median NRMSE over the strong motion of
# the transverse deck channels (7, 9, 4) beside the "deck = nearest ground"
# baseline; then the wall time of the whole run and the frequency against
# amplitude figure in OUT (default out/events).
# Usage: benches/painter_street_events.sh DIR [splinewatch binary] [OUT]
set -euo pipefail
dir="$1"
bin="${2:-target/release/splinewatch}"
out="${3:-out/events}"
mkdir -p "$out"
start=$(date +%s.%N)
"$bin" events --config ${CONFIG:-config/painter-street.toml} --json --plot "$out" --out "$out/events.mcap" "$dir"/*.zip \
  > "$out/events.jsonl" 2> "$out/events.log"
end=$(date +%s.%N)
python3 - "$out/events.jsonl" <<'PY'
import json, statistics, sys
tr = ("ch7", "ch9", "ch4")
wins = total = 0
print(f"{'start':10s} {'event':28s} {'pga':>6s} {'modes (Hz)':24s} {'ky west/bent/east (1e8 N/m)':28s} {'zeta':>5s} {'model':>6s} {'fit':>5s} {'fcst':>5s} {'base':>5s}")
for line in open(sys.argv[1]):
    d = json.loads(line)
    if d["skipped"]:
        print(f"{d['event']}: skipped: {d['skipped']}")
        continue
    f = d["forecast"]
    fc = base = "-"
    if f:
        a = statistics.median(c["nrmse_strong"] for c in f["channels"] if c["sensor"] in tr)
        b = statistics.median(c["nrmse_strong"] for c in f["baseline"] if c["sensor"] in tr)
        fc, base = f"{a:.2f}", f"{b:.2f}"
        total += 1
        wins += a < b
    modes = ",".join(f"{m['frequency_hz']:.2f}" for m in d["modes"]) or "-"
    ky = "/".join(f"{p['value'] / 1e8:.2f}" for p in d["parameters"] if p["name"].endswith(".ky"))
    zeta = next((f"{p['value']:.3f}" for p in d["parameters"] if p["name"].startswith("damping")), "-")
    u = d["update"]
    print(f"{d['start'][:10]:10s} {d['event'][:28]:28s} {d['pga_ground']:6.2f} {modes:24s} {ky:28s} {zeta:>5s} {u['model_mode_hz'] or float('nan'):6.2f} {u['relative_residual']:5.2f} {fc:>5s} {base:>5s}")
print(f"forecast better than the baseline in {wins} of {total} events")
PY
echo "wall time of the events run: $(python3 -c "print(f'{$end - $start:.1f} s')")"
