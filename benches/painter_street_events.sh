#!/usr/bin/env bash
# Runs every Painter Street record in DIR (the station zips of CSMIP station
# 89324, e.g. github chrystalchern/mdof notebooks/uploads/CE89324) through
# one `splinewatch events` run with config/painter-street.toml (or $CONFIG), and prints per
# event the ground's peak, the identified modes, the updated stiffnesses
# (the support lines' lateral ones), the updated model's dominant mode,
# the update's fit and the forecast's median NRMSE over the strong motion of
# all eight deck channels, of the four vertical and of the three transverse
# ones beside the "deck = nearest ground" baseline's, with the events where
# the forecast wins in each set and on each channel; then the wall time of
# the whole run and the frequency against amplitude figure in OUT (default
# out/events), and each identified mode against the forecast's model (the
# model mode nearest it by shape). CONFIG=config/painter-street-bridge.toml
# runs the whole bridge.
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
# The deck channels by direction (the station's sensor drawing).
groups = {"all": ("ch4", "ch5", "ch6", "ch7", "ch8", "ch9", "ch10", "ch11"),
          "vertical": ("ch5", "ch6", "ch8", "ch10"), "transverse": ("ch4", "ch7", "ch9")}
wins = {g: 0 for g in groups}
channel_wins = {c: 0 for c in groups["all"]}
total = 0
print(f"{'start':10s} {'event':28s} {'pga':>6s} {'modes (Hz)':24s} {'stiffnesses updated (1e8)':26s} {'zeta':>5s} {'model':>6s} {'fit':>5s}  forecast/baseline: {'  '.join(f'{g:>10s}' for g in groups)}")
for line in open(sys.argv[1]):
    d = json.loads(line)
    if d["skipped"]:
        print(f"{d['event']}: skipped: {d['skipped']}")
        continue
    f = d["forecast"]
    medians = ""
    if f:
        fc = {c["sensor"]: c["nrmse_strong"] for c in f["channels"]}
        base = {c["sensor"]: c["nrmse_strong"] for c in f["baseline"]}
        total += 1
        for g, chans in groups.items():
            present = [c for c in chans if c in fc]
            a = statistics.median(fc[c] for c in present)
            b = statistics.median(base[c] for c in present)
            wins[g] += a < b
            medians += f"  {a:4.2f}/{b:4.2f}"
        for c in channel_wins:
            channel_wins[c] += c in fc and fc[c] < base[c]
    modes = ",".join(f"{m['frequency_hz']:.2f}" for m in d["modes"]) or "-"
    k = "/".join(f"{p['value'] / 1e8:.2f}" for p in d["parameters"] if not p["name"].startswith("damping"))
    zeta = next((f"{p['value']:.3f}" for p in d["parameters"] if p["name"].startswith("damping")), "-")
    u = d["update"]
    print(f"{d['start'][:10]:10s} {d['event'][:28]:28s} {d['pga_ground']:6.2f} {modes:24s} {k:26s} {zeta:>5s} {u['model_mode_hz'] or float('nan'):6.2f} {u['relative_residual']:5.2f} {medians}")
for g in groups:
    print(f"forecast's median NRMSE below the baseline's, {g} channels: {wins[g]} of {total} events")
print("per channel: " + ", ".join(f"{c} {n}" for c, n in channel_wins.items()))
# Each identified mode against the forecast's model (the config's values for
# the first event): the model mode nearest it by shape (MAC at the deck
# channels), its frequency and the gap. A vertical mode: over half its
# squared shape on the vertical channels; the first vertical mode identified
# at 3.2-3.7 Hz, the second at 4.4-5.2 Hz. It "pairs" (the acceptance) when
# updating pairs it (MAC >= [updating] min_mac within max_frequency_gap) and
# the gap is within 5 %.
print("identified modes against the forecast's model, nearest by shape (model mode: Hz, MAC, gap):")
shown = {"first vertical": [0, 0], "second vertical": [0, 0]}
damping = {"first vertical": [], "second vertical": []}
for line in open(sys.argv[1]):
    d = json.loads(line)
    if d["skipped"] or not d["modes"]:
        continue
    cells = []
    for m in d["modes"]:
        share = {s["sensor"]: s["re"] ** 2 + s["im"] ** 2 for s in m["shape"]}
        vertical = sum(share.get(c, 0) for c in groups["vertical"]) > 0.5 * sum(share.values())
        n = m.get("model")
        f = m["frequency_hz"]
        which = ("first vertical" if 3.2 <= f <= 3.7 else "second vertical" if 4.4 <= f <= 5.2 else None) if vertical else None
        if which and n:
            shown[which][0] += 1
            shown[which][1] += n["pairs"] and abs(n["frequency_gap"]) <= 0.05
        if which and n and n["pairs"]:
            damping[which].append((m["damping_ratio"], n["damping_ratio"], n["frequency_gap"]))
        cells.append(f"{f:.2f}{'v' if vertical else ''} -> {n['mode']}: {n['frequency_hz']:.2f} {n['mac']:.2f} {100 * n['frequency_gap']:+.0f}%{' pairs' if n['pairs'] else ''}" if n else f"{f:.2f}: -")
    print(f"{d['start'][:10]:10s} {d['event'][:28]:28s} " + "; ".join(cells))
for which, (seen, paired) in shown.items():
    print(f"{which} mode identified on {seen} events, paired with the model's within 5 %: {paired}")
# The damping of the paired modes: the identified range against the forecast
# model's zeta for the same modes.
for which, pairs in damping.items():
    if pairs:
        ident = [100 * p[0] for p in pairs]
        model = [100 * p[1] for p in pairs]
        print(f"{which} mode's damping where paired: identified {min(ident):.1f}-{max(ident):.1f} %, "
              f"the forecast's model {min(model):.1f}-{max(model):.1f} %")
# Whether the model's damping grows with its frequency's miss: each paired
# mode's gap against the forecast model's damping, and Spearman's rank
# correlation of the two (ties share their mean rank).
def ranks(x):
    order = sorted(range(len(x)), key=lambda i: x[i])
    r = [0.0] * len(x)
    i = 0
    while i < len(order):
        j = i
        while j + 1 < len(order) and x[order[j + 1]] == x[order[i]]:
            j += 1
        for k in range(i, j + 1):
            r[order[k]] = (i + j) / 2 + 1
        i = j + 1
    return r
def spearman(a, b):
    ra, rb = ranks(a), ranks(b)
    ma, mb = statistics.mean(ra), statistics.mean(rb)
    cov = sum((x - ma) * (y - mb) for x, y in zip(ra, rb))
    return cov / (sum((x - ma) ** 2 for x in ra) * sum((y - mb) ** 2 for y in rb)) ** 0.5
for which, pairs in damping.items():
    if len(pairs) >= 3:
        pairs = sorted(pairs, key=lambda p: abs(p[2]))
        cells = ", ".join(f"{100 * p[2]:+.1f} % {100 * p[1]:.1f} %" for p in pairs)
        rho = spearman([abs(p[2]) for p in pairs], [p[1] for p in pairs])
        print(f"{which} mode where paired, frequency gap and the model's damping: {cells}; "
              f"Spearman's rank correlation of |gap| and damping {rho:.2f} ({len(pairs)} events)")
PY
echo "wall time of the events run: $(python3 -c "print(f'{$end - $start:.1f} s')")"
