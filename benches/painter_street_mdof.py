"""Painter Street, event by event, side by side with mdof (issue 45's scale).

For every record of CSMIP station 89324 in DIR (the station zips of github
chrystalchern/mdof, notebooks/uploads/CE89324), in time order:

- mdof (`pip install mdof`) reads it (quakeio, as its notebook
  06_MIMO_History does) and identifies a SRIM realization from the
  transverse channels of `channel_conf.py` (inputs 3, 17, 20; outputs 7, 9,
  4) with the notebook's settings (order 12, horizon 190), and reports its
  modes (`modal.system_modes`);
- the realization of the *previous* event is driven by this event's ground
  channels (`mdof.simulate.simulate`): mdof's forecast of this event;
- `splinewatch predict` forecasts the same event with
  config/painter-street.toml at its (hand-set) values;
- `splinewatch events` (one run over every record) forecasts it with the
  physical model updated on the events before it (issue 45's honest
  forecast), config/painter-street.toml or the config in $CONFIG (e.g.
  config/painter-street-bridge.toml, the whole bridge);
- `splinewatch events` on the starter config `splinewatch station` writes
  from the same zips (no model) forecasts it by the realization identified
  on the previous event (SRIM of every ground group to every deck channel,
  `[events] realization_order`), mdof's method in splinewatch;

and both forecasts are scored the same way: NRMSE over the strong motion
(5-95 % of the energy of the ground channels), median over channels 7, 9, 4.
Usage: .venv/bin/python benches/painter_street_mdof.py DIR [splinewatch]
"""

import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import mdof
import quakeio
from mdof import modal
from mdof.simulate import simulate
from mdof.utilities import extract_channels

INPUTS, OUTPUTS = [3, 17, 20], [7, 9, 4]
SETTINGS = dict(order=12, horizon=190, nc=190)


def strong_span(ground):
    energy = np.cumsum(np.sum(ground**2, axis=0))
    total = energy[-1]
    return int(np.searchsorted(energy, 0.05 * total)), int(np.searchsorted(energy, 0.95 * total)) + 1


def nrmse(pred, meas):
    return float(np.sqrt(np.mean((pred - meas) ** 2)) / np.sqrt(np.mean(meas**2)))


def main():
    directory = Path(sys.argv[1])
    binary = sys.argv[2] if len(sys.argv) > 2 else "target/release/splinewatch"
    events = []
    for path in sorted(directory.glob("*.zip")):
        event = quakeio.read(path, exclusions=["*filter*"])
        inputs, dt = extract_channels(event, INPUTS)
        outputs, _ = extract_channels(event, OUTPUTS)
        sw = json.loads(
            subprocess.run(
                [binary, "predict", "--config", "config/painter-street.toml", str(path), "--json"],
                capture_output=True,
                check=True,
                text=True,
            ).stdout
        )
        events.append((sw["start"], path.name, inputs, outputs, dt, sw))
    events.sort()
    chain = {}
    out = subprocess.run(
        [binary, "events", "--config", os.environ.get("CONFIG", "config/painter-street.toml"), "--json",
         *map(str, sorted(directory.glob("*.zip")))],
        capture_output=True,
        check=True,
        text=True,
    ).stdout
    for line in out.splitlines():
        d = json.loads(line)
        if d["forecast"]:
            scores = {c["sensor"]: c["nrmse_strong"] for c in d["forecast"]["channels"]}
            chain[d["event"]] = statistics.median(scores[f"ch{c}"] for c in OUTPUTS)
    # Without a model: the station's starter config, the realization chain.
    zips = [str(p) for p in sorted(directory.glob("*.zip"))]
    free = {}
    with tempfile.TemporaryDirectory() as tmp:
        station = f"{tmp}/station.toml"
        subprocess.run([binary, "station", *zips, "--out", station], capture_output=True, check=True)
        t0 = time.perf_counter()
        out = subprocess.run(
            [binary, "events", "--config", station, "--json", *zips], capture_output=True, check=True, text=True
        ).stdout
        free_seconds = time.perf_counter() - t0
    for line in out.splitlines():
        d = json.loads(line)
        if d["forecast"]:
            scores = {c["sensor"]: c["nrmse_strong"] for c in d["forecast"]["channels"]}
            if all(f"ch{c}" in scores for c in OUTPUTS):
                free[d["event"]] = statistics.median(scores[f"ch{c}"] for c in OUTPUTS)
    previous = None
    tally = {"events": [0, 0], "sw": [0, 0], "free": [0, 0]}
    print(
        f"{'start':20s} {'event':44s} {'mdof s':>7s} {'modes (Hz, damping %) by mdof SRIM':40s} "
        f"{'mdof prev':>9s} {'sw':>6s} {'events':>6s} {'no model':>8s}"
    )
    for start, name, inputs, outputs, dt, sw in events:
        t0 = time.perf_counter()
        realization = mdof.sysid(inputs, outputs, dt=dt, method="srim", **SETTINGS)
        seconds = time.perf_counter() - t0
        modes = modal.system_modes(realization, dt)
        listed = sorted((m["freq"], 100 * m["damp"]) for m in modes.values() if 0.5 < m["freq"] < 12)
        text = ", ".join(f"{f:.2f} ({z:.1f})" for f, z in listed[:4])
        s0, s1 = strong_span(inputs)
        forecast = float("nan")
        if previous is not None:
            predicted = simulate(previous, inputs)
            forecast = statistics.median(nrmse(predicted[k, s0:s1], outputs[k, s0:s1]) for k in range(len(OUTPUTS)))
        ours = {c["sensor"]: c["nrmse_strong"] for c in sw["channels"]}
        sw_median = statistics.median(ours[f"ch{c}"] for c in OUTPUTS)
        updated = chain.get(name, float("nan"))
        event_name = name.removesuffix(".zip")
        model_free = free.get(event_name, free.get(name, float("nan")))
        print(
            f"{start[:19]:20s} {name:44s} {seconds:7.2f} {text:40s} {forecast:9.3f} {sw_median:6.3f} "
            f"{updated:6.3f} {model_free:8.3f}"
        )
        previous = realization
        if np.isfinite(forecast):
            for key, ours_here in (("events", updated), ("sw", sw_median), ("free", model_free)):
                if np.isfinite(ours_here):
                    tally[key][0] += ours_here <= forecast
                    tally[key][1] += 1
    print(f"events without a model (the realization chain): {free_seconds:.1f} s for {len(zips)} records")
    for key, label in (
        ("events", "the events chain's forecast"),
        ("sw", "the hand-set model's"),
        ("free", "the realization chain's (no model)"),
    ):
        print(f"{label} at or below mdof's (previous event's realization) in {tally[key][0]} of {tally[key][1]} events")


if __name__ == "__main__":
    main()
