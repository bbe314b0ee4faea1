"""The peak of the H1 transmissibility from channel 3 (the bent's base,
transverse) to channel 7 (the bent's top, transverse) of every Painter
Street record in DIR (CSMIP station 89324's CESMD zips, e.g. github
chrystalchern/mdof notebooks/uploads/CE89324): the reference of the
frequency-domain identification's transverse mode (scipy's Welch: Hann
segments of 8 s, half overlapping; H1 = P_xy / P_xx, the peak of |H1|
between 2 and 6 Hz), with the ground's peak acceleration (channel 3's).
quakeio reads the records, as mdof's notebooks do.
Usage: python benches/painter_street_h1_peaks.py DIR [--json OUT]"""

import json
import sys
from pathlib import Path

import numpy as np
import quakeio
from scipy import signal


def channel(event, number):
    found = event.match("l", station_channel=f"{number}")
    return None if found is None else (np.asarray(found.accel.data, float), found.accel["time_step"])


def h1_peak(path, segment_seconds=8.0):
    """(peak of |H1| 3 -> 7 over 2-6 Hz in Hz, channel 3's peak in cm/s2, fs),
    or None without channel 3 or 7; Welch segments of `segment_seconds`, or
    one peak per length when it is a tuple (the record read once)."""
    event = quakeio.read(str(path), exclusions=["*filter*"])
    base, top = channel(event, 3), channel(event, 7)
    if base is None or top is None:
        return None
    (x, dt), (y, _) = base, top
    n = min(len(x), len(y))
    fs = 1.0 / dt

    def peak(seconds):
        segment = int(round(seconds * fs))
        f, pxx = signal.welch(x[:n], fs, window="hann", nperseg=segment, noverlap=segment // 2)
        _, pxy = signal.csd(x[:n], y[:n], fs, window="hann", nperseg=segment, noverlap=segment // 2)
        h1 = pxy / pxx
        band = (f >= 2.0) & (f <= 6.0)
        return float(f[band][np.argmax(np.abs(h1[band]))])

    peaks = tuple(map(peak, segment_seconds)) if isinstance(segment_seconds, tuple) else peak(segment_seconds)
    return peaks, float(np.abs(x).max()), fs


def main():
    directory = Path(sys.argv[1])
    rows = []
    for path in sorted(directory.glob("*.zip")):
        found = h1_peak(path)
        if found is None:
            print(f"{path.name}: no channel 3 or 7", file=sys.stderr)
            continue
        peak, ground, fs = found
        rows.append({"record": path.name, "fs": fs, "pga_ground_cm_s2": ground, "h1_peak_hz": peak})
        print(f"{path.name:52s} fs {fs:5.0f} Hz  ch3 peak {ground:7.2f} cm/s2  H1 3->7 peak {peak:.3f} Hz")
    if "--json" in sys.argv:
        Path(sys.argv[sys.argv.index("--json") + 1]).write_text(json.dumps(rows, indent=1) + "\n")


if __name__ == "__main__":
    main()
