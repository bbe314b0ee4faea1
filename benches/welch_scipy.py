"""The scipy side of benches/welch.rs: csd(f, X) for 12 outputs, welch of f
and of X, H1 and coherence, 1 h at 256 Hz, 8 s Hann segments, 50 % overlap.
Run: python3 benches/welch_scipy.py"""
import timeit

import numpy as np
from scipy import signal

fs, n = 256.0, 3600 * 256
rng = np.random.default_rng(1)
f = rng.random(n) - 0.5
x = np.stack([f * (k + 1) + rng.random(n) - 0.5 for k in range(12)])
kw = dict(fs=fs, window="hann", nperseg=2048, noverlap=1024, detrend="constant")


def run():
    _, pfx = signal.csd(f, x, **kw)
    _, pff = signal.welch(f, **kw)
    _, pxx = signal.welch(x, **kw)
    h1 = pfx / pff
    coh = np.abs(pfx) ** 2 / (pff * pxx)
    return h1, coh


times = timeit.repeat(run, number=1, repeat=5)
print(f"scipy {signal.__name__}: fastest {min(times) * 1e3:.1f} ms, median {sorted(times)[2] * 1e3:.1f} ms")
