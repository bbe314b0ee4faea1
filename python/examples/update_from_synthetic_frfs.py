"""FRF-based updating (Carminelli & Catania 2011, §3-4) from Python.

    python update_from_synthetic_frfs.py [--noise 0.02]

Makes "measured" FRFs from the truth model (config/sinello-truth.toml, the
paper's experiment: a damping curve the model cannot represent) with
complex noise, updates the bundled model (config/sinello.toml) on them from
every spring coefficient set 40 % low (the parameters are a dict you can
change), and prints each one's start, estimate ± std and truth.
"""

import argparse
import pathlib

import splinewatch

REPO = pathlib.Path(__file__).resolve().parents[2]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--noise", type=float, default=0.02)
    args = parser.parse_args()

    truth = splinewatch.Model.from_config(REPO / "config/sinello-truth.toml")
    measured = truth.synthetic_frf(["P1"], ["P2", "P3", "P5", "P8", "P11"], 0.5, 80.0, 0.1,
                                   noise=args.noise, seed=4)
    model = splinewatch.Model.from_config(REPO / "config/sinello.toml")
    for name in model.parameters:
        if not name.startswith("damping"):
            model.parameters[name] *= 0.6
    start = dict(model.parameters)
    update = model.update(frf=measured)
    print(update)
    print("parameter        start          estimate ± std              truth      error/std")
    for name, value in update.values.items():
        if name not in truth.parameters:
            continue
        std = update.std[name]
        print(f"{name:10s} {start[name]:12.4e}  {value:12.4e} ± {std:9.2e}  {truth.parameters[name]:12.4e}  "
              f"{(value - truth.parameters[name]) / std:8.2f}")


if __name__ == "__main__":
    main()
