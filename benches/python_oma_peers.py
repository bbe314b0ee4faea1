"""splinewatch's Python package beside KOMA and pyOMA2 on one window (issue 46).

The same 10-minute, 12-channel, 256 Hz ambient window of the bundled deck
(SSI-cov, 40 block rows, orders 2..120 step 2 for all three), in one run:
each tool's modes (frequency, damping) paired with the model's bending modes
below 80 Hz, and its wall time (median of three runs, the modes' automatic
selection included: splinewatch's stabilisation and clustering with
first-order uncertainty; KOMA's find_stable_poles + HDBSCAN PoleClusterer,
as benches/oma_koma.py; pyOMA2's SSI with its "Reynders" automatic
clustering; and pyOMA2 with its uncertainty (calc_unc): its clustering
fails then in pyOMA_2 1.4.2 (an IndexError), so its modes are picked with
its `mpe` at the frequencies its clustering found without uncertainty).

    splinewatch simulate --config config/sinello-ambient.toml --duration 600 \\
        --excitation ambient --seed 1 --out /tmp/ambient600.mcap
    python benches/python_oma_peers.py /tmp/ambient600.mcap

in a venv with the package (pip install ./python), koma-python and pyOMA_2.
"""

import logging
import os
import pathlib
import statistics
import sys
import time
import warnings

import numpy as np

import splinewatch

os.environ.setdefault("TQDM_DISABLE", "1")  # pyOMA2's progress bars
REPO = pathlib.Path(__file__).resolve().parents[1]
FS, BLOCK_ROWS, ORDERS = 256.0, 40, (2, 120, 2)


def timed(run, repeats=3):
    times, result = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = run()
        times.append(time.perf_counter() - t0)
    return result, statistics.median(times)


def with_splinewatch(data):
    modes = splinewatch.oma(data, FS, band=(0.5, 80.0), block_rows=BLOCK_ROWS, orders=ORDERS)
    return modes.frequency, modes.damping


def with_koma(data):
    import koma.clustering
    import koma.oma

    lambd, phi, orders = koma.oma.covssi(data, FS, BLOCK_ROWS, list(range(ORDERS[0], ORDERS[1] + 1, ORDERS[2])),
                                         showinfo=False)
    stab = koma.oma.find_stable_poles(lambd, phi, orders, 3, stabcrit={"freq": 0.01, "damping": 0.25, "mac": 0.02},
                                      valid_range={"freq": [0, np.inf], "damping": [0, 0.2]}, indicator="freq")
    clusterer = koma.clustering.PoleClusterer(stab[0], stab[1], stab[2], min_samples=10, min_cluster_size=10)
    grouped = koma.clustering.group_clusters(*clusterer.postprocess(prob_threshold=0.5))
    # group_clusters: (xi, omega_n, phi, order, probability, index) per cluster
    zeta = np.array([np.median(x) for x in grouped[0]])
    f = np.array([np.median(w) for w in grouped[1]]) / (2 * np.pi)
    keep = (f > 0.5) & (f < 80.0)
    order = np.argsort(f[keep])
    return f[keep][order], zeta[keep][order]


def with_pyoma2(data, picked=None):
    """pyOMA2's SSI-cov and automatic clustering; with `picked` (frequencies), its
    uncertainty (calc_unc) and `mpe` at those frequencies instead."""
    from pyoma2.algorithms import SSI
    from pyoma2.algorithms.data.run_params import Clustering
    from pyoma2.setup import SingleSetup

    setup = SingleSetup(data, fs=FS)
    ssi = SSI(name="ssicov", method="cov", br=BLOCK_ROWS, ordmin=ORDERS[0], ordmax=ORDERS[1], step=ORDERS[2],
              calc_unc=picked is not None)
    setup.add_algorithms(ssi)
    setup.run_all()
    if picked is not None:
        ssi.mpe(sel_freq=list(picked), order_in="find_min")
        fn, xi = np.asarray(ssi.result.Fn), np.asarray(ssi.result.Xi)
    else:
        ssi.add_clustering(Clustering(name="auto", quick="Reynders", freqlim=(0.5, 80.0)))
        ssi.run_all_clustering()
        result = ssi.result.clustering_results["auto"]
        fn, xi = np.asarray(result.Fn), np.asarray(result.Xi)
    order = np.argsort(fn)
    return fn[order], xi[order]


def main():
    channels = splinewatch.read_recording(sys.argv[1])
    names = [f"P{k}" for k in range(1, 13)]
    data = np.column_stack([channels[n].data for n in names])
    model = splinewatch.Model.from_config(REPO / "config/sinello-ambient.toml").modes()
    exact = [f for f, kind in zip(model["frequency"], model["kind"]) if kind == "bending" and f < 80.0]
    print(f"window: {data.shape[0]} samples × {data.shape[1]} channels at {FS:g} Hz "
          f"({data.shape[0] / FS / 60:.0f} min); model: {len(exact)} bending modes below 80 Hz")

    logging.disable(logging.WARNING)
    warnings.simplefilter("ignore")
    runs = {"splinewatch": lambda: with_splinewatch(data), "KOMA": lambda: with_koma(data),
            "pyOMA2": lambda: with_pyoma2(data),
            "pyOMA2 + uncertainty": lambda: with_pyoma2(data, picked=results["pyOMA2"][0])}
    results = {}
    for name, run in runs.items():
        try:
            (f, zeta), seconds = timed(run, repeats=1 if name.startswith("pyOMA2") else 3)
        except Exception as e:  # a peer that fails is reported, not hidden
            print(f"{name}: failed: {e!r}")
            continue
        results[name] = (np.asarray(f), np.asarray(zeta), seconds)

    print("\n| model (Hz) | " + " | ".join(f"{n} f (Hz) / ζ (%)" for n in results) + " |")
    print("| --- | " + " | ".join("---" for _ in results) + " |")
    for fm in exact:
        cells = []
        for f, zeta, _ in results.values():
            if len(f) == 0:
                cells.append("–")
                continue
            k = int(np.argmin(np.abs(f - fm)))
            cells.append(f"{f[k]:.3f} / {100 * zeta[k]:.2f}" if abs(f[k] - fm) / fm < 0.02 else "–")
        print(f"| {fm:.3f} | " + " | ".join(cells) + " |")
    print("| modes found | " + " | ".join(str(len(f)) for f, _, _ in results.values()) + " |")
    print("| wall time (s) | " + " | ".join(f"{s:.2f}" for _, _, s in results.values()) + " |")
    print("\n(splinewatch and KOMA: median of 3 runs; pyOMA2: one run each)")


if __name__ == "__main__":
    main()
