"""`splinewatch identify` side by side with mdof's SRIM on the same event, in one run.

The event: a station zip of CSMIP station 89324 (default the committed 2012
record, 60 s at 200 Hz, 17 channels). splinewatch: the whole CLI (`identify
--config config/painter-street.toml ZIP --json`: import of the zip, SRIM over
orders 2-60 with stabilisation and jackknife uncertainty, all 9 ground and 8
deck channels), timed over five runs. mdof: its SRIM as its notebook runs it
(quakeio reading the zip, `mdof.sysid(..., method="srim", order=12,
horizon=190)` on the transverse channels 3, 17, 20 -> 7, 9, 4, then
`modal.system_modes`), timed the same way. Prints the modes each reports and
the times.
Usage: .venv/bin/python benches/identify_mdof.py [ZIP] [splinewatch binary]
"""

import json
import statistics
import subprocess
import sys
import time

import mdof
import quakeio
from mdof import modal
from mdof.utilities import extract_channels

ZIP = sys.argv[1] if len(sys.argv) > 1 else "tests/fixtures/painter-street/RioDell_14Sep2012_71842255_ce89324p.zip"
BINARY = sys.argv[2] if len(sys.argv) > 2 else "target/release/splinewatch"
RUNS = 5


def splinewatch():
    out = subprocess.run(
        [BINARY, "identify", "--config", "config/painter-street.toml", ZIP, "--json"],
        capture_output=True,
        text=True,
    )
    if out.returncode != 0:
        return out.stderr.strip().splitlines()[-1]
    return [(round(m["frequency_hz"], 2), m["frequency_std_hz"]) for m in json.loads(out.stdout)["modes"]]


def mdof_srim():
    event = quakeio.read(ZIP, exclusions=["*filter*"])
    inputs, dt = extract_channels(event, [3, 17, 20])
    outputs, _ = extract_channels(event, [7, 9, 4])
    realization = mdof.sysid(inputs, outputs, dt=dt, method="srim", order=12, horizon=190, nc=190)
    modes = modal.system_modes(realization, dt)
    return sorted((round(m["freq"], 2), round(100 * m["damp"], 1)) for m in modes.values() if 0.5 < m["freq"] < 25)


def timed(run):
    times, result = [], None
    for _ in range(RUNS):
        t0 = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - t0)
    return result, times


sw, sw_times = timed(splinewatch)
md, md_times = timed(mdof_srim)
print(f"event: {ZIP}")
print(f"splinewatch identify (whole CLI, 17 channels): {min(sw_times):.3f}-{max(sw_times):.3f} s, median {statistics.median(sw_times):.3f} s")
print(f"  modes (Hz, std Hz): {sw}")
print(f"mdof SRIM (read + sysid + modes, 6 channels): {min(md_times):.3f}-{max(md_times):.3f} s, median {statistics.median(md_times):.3f} s")
print(f"  modes (Hz, damping %): {md}")
