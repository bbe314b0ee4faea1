#!/usr/bin/env bash
# Every record of the strong-motion stations in DIR (one folder per station
# of CESMD zips, e.g. github chrystalchern/mdof notebooks/uploads, whose
# folders CE89324, hayward, capistrano, crowley, meloland hold Painter
# Street, Hayward, Capistrano Beach, Crowley Lake and Meloland) through
# `splinewatch station` (the starter config, no hand edits) and then one
# `splinewatch events` run without a model: per station the records, the
# events identified (a mode or more), skipped (with their reasons) and
# judged, each event's identified modes against its ground peak, and the
# wall times of both commands. OUT (default out/stations) keeps the configs
# and the events' JSON lines.
# Usage: benches/stations_events.sh DIR [splinewatch binary] [OUT]
set -euo pipefail
dir="$1"
bin="${2:-target/release/splinewatch}"
out="${3:-out/stations}"
mkdir -p "$out"
for station in "$dir"/*/; do
  name=$(basename "$station")
  zips=$(find "$station" -maxdepth 1 -type f \( -iname '*.zip' \) -size +0 | sort)
  [ -z "$zips" ] && continue
  t0=$(date +%s.%N)
  # shellcheck disable=SC2086
  "$bin" station $zips --out "$out/$name.toml" 2> "$out/$name.station.log" || { echo "$name: station refused: $(tail -1 "$out/$name.station.log")"; continue; }
  t1=$(date +%s.%N)
  # shellcheck disable=SC2086
  "$bin" events --config "$out/$name.toml" --json $zips > "$out/$name.jsonl" 2> "$out/$name.events.log" || true
  t2=$(date +%s.%N)
  python3 - "$name" "$out/$name.jsonl" "$(echo "$t1 - $t0" | bc)" "$(echo "$t2 - $t1" | bc)" "$(grep -c '^guessed' "$out/$name.station.log" || true)" <<'PY'
import json, sys
name, path, station_s, events_s, guesses = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4]), sys.argv[5]
lines = [json.loads(l) for l in open(path)]
identified = [d for d in lines if not d["skipped"] and d["modes"]]
skipped = [d for d in lines if d["skipped"]]
judged = [d for d in lines if d.get("verdict")]
states = {}
for d in judged:
    states[d["verdict"]["state"]] = states.get(d["verdict"]["state"], 0) + 1
print(f"## {name}: {len(lines)} records; station {station_s:.2f} s ({guesses} guesses), events {events_s:.1f} s")
print(f"identified {len(identified)}, skipped {len(skipped)}, verdicts {states}")
for d in lines:
    modes = ", ".join(f"{m['frequency_hz']:.2f}±{m['frequency_std_hz'] if m.get('frequency_std_hz') is not None else float('nan'):.2f}" for m in d["modes"][:4])
    tail = d["skipped"] or (d["verdict"] or {}).get("state", "")
    print(f"  {str(d['start'])[:19]:19s} pga {d['pga_ground'] or 0:7.3f} m/s2  modes [{modes}]  {tail}")
PY
done
