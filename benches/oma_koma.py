"""KOMA (koma-python) on the same 10-minute, 12-channel, 256 Hz ambient
window as `cargo bench --bench oma`: covssi (40 block rows, orders 2..120
step 2), find_stable_poles and PoleClusterer; the median of three runs.

Write the window first:
    SPLINEWATCH_BENCH_OMA_MCAP=/tmp/oma_bench.mcap cargo bench --bench oma
then, in a venv with numpy, scipy, scikit-learn, mcap, cbor2, koma-python:
    python3 benches/oma_koma.py /tmp/oma_bench.mcap
"""
import sys
import time

import cbor2
import numpy as np
from mcap.reader import make_reader

import koma.clustering
import koma.oma

blocks = {}
with open(sys.argv[1], "rb") as f:
    for _, _, message in make_reader(f).iter_messages():
        block = cbor2.loads(message.data)
        samples = block["data"]
        samples = np.frombuffer(samples.value, dtype="<f8") if hasattr(samples, "tag") else np.asarray(samples)
        blocks.setdefault(block["name"], []).append((block["start_timestamp"], samples))
data = np.array([np.concatenate([s for _, s in sorted(blocks[f"P{k}"], key=lambda b: b[0])])
                 for k in range(1, 13)]).T
times = []
for _ in range(3):
    t0 = time.perf_counter()
    lambd, phi, orders = koma.oma.covssi(data, 256.0, 40, list(range(2, 121, 2)), showinfo=False)
    stab = koma.oma.find_stable_poles(lambd, phi, orders, 3, stabcrit={"freq": 0.01, "damping": 0.25, "mac": 0.02},
                                      valid_range={"freq": [0, np.inf], "damping": [0, 0.2]}, indicator="freq")
    clusterer = koma.clustering.PoleClusterer(stab[0], stab[1], stab[2], min_samples=10, min_cluster_size=10)
    grouped = koma.clustering.group_clusters(*clusterer.postprocess(prob_threshold=0.5))
    times.append(time.perf_counter() - t0)
print(f"koma-python: {len(grouped[1])} clusters, median {sorted(times)[1]:.2f} s "
      f"({data.shape[0]} samples × {data.shape[1]} channels)")
