"""Large arrays are not copied needlessly: measured as the peak resident
memory a call adds (Linux's VmHWM, reset before the call), in a fresh
interpreter, on a 96 MB record."""

import json
import subprocess
import sys

import pytest

SNIPPET = """
import json, sys
import numpy as np
import splinewatch


def status(key):  # kB figures of /proc/self/status
    for line in open("/proc/self/status"):
        if line.startswith(key + ":"):
            return int(line.split()[1]) * 1024


order = sys.argv[1]
rng = np.random.default_rng(0)
data = np.empty((1_000_000, 12), order=order)  # 96 MB, samples × channels
rng.standard_normal(out=data if order == "C" else data.T)
force = np.empty(len(data))
rng.standard_normal(out=force)
with open("/proc/self/clear_refs", "w") as f:  # reset the peak (VmHWM) to the current RSS
    f.write("5")
before = status("VmRSS")
f, h, coherence = splinewatch.frf(force, data, 100.0, segment_seconds=10.0)
print(json.dumps({"added": status("VmHWM") - before, "size": data.nbytes}))
"""


def _added(order):
    done = subprocess.run([sys.executable, "-c", SNIPPET, order], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


@pytest.mark.skipif(sys.platform != "linux", reason="VmHWM and clear_refs are Linux's")
def test_fortran_ordered_records_are_read_in_place_and_c_ordered_ones_copied_once():
    f_order, c_order = _added("F"), _added("C")
    size = f_order["size"]
    # In place: the spectra and FFT buffers only (a few MB), not a copy of the record.
    assert f_order["added"] < 0.1 * size, f_order
    # C order: each channel gathered once (one copy of the record), never more.
    assert 0.8 * size < c_order["added"] < 1.5 * size, c_order
