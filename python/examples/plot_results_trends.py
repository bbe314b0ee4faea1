"""Trends of a results file: each parameter's value and ±2σ band over time.

    python plot_results_trends.py RESULTS.mcap [--save trends.png] [--parameters west.k1 east.k2]

Prints the first and last value of every parameter; with --save (needs
matplotlib) draws them, and the monitoring state when the file has one.
"""

import argparse

import numpy as np

import splinewatch


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("results")
    parser.add_argument("--save")
    parser.add_argument("--parameters", nargs="*")
    args = parser.parse_args()

    results = splinewatch.read_results(args.results)
    print(results)
    names = args.parameters or [n for n in results.parameters if not n.startswith("damping")]
    for name in names:
        p = results.parameters[name]
        print(f"{name:12s} {len(p['value']):4d} updates  {p['value'][0]:.4e} → {p['value'][-1]:.4e}")

    if args.save:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(len(names), 1, figsize=(8, 1.8 * len(names)), sharex=True, squeeze=False)
        for ax, name in zip(axes[:, 0], names):
            p = results.parameters[name]
            ax.plot(p["time"], p["value"], ".-", ms=3)
            ok = np.isfinite(p["std"])
            ax.fill_between(p["time"][ok], (p["value"] - 2 * p["std"])[ok], (p["value"] + 2 * p["std"])[ok],
                            alpha=0.3)
            ax.set_ylabel(name)
        alarms = results.monitoring["time"][results.monitoring["state"] == "alarm"]
        for ax in axes[:, 0]:
            for t in alarms:
                ax.axvline(t, color="C3", lw=0.5)
        fig.savefig(args.save, dpi=120, bbox_inches="tight")
        print(f"wrote {args.save}")


if __name__ == "__main__":
    main()
