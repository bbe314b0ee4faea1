"""A deck's modes and FRFs from a splinewatch config.

    python model_modes_and_frfs.py [CONFIG] [--input P1] [--output P2]

Prints the model's first bending modes with their shapes at the sensors,
the accelerance between two sensors around the first one, and what
halving a support's stiffness does to the frequencies.
"""

import argparse
import pathlib

import numpy as np

import splinewatch

REPO = pathlib.Path(__file__).resolve().parents[2]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", nargs="?", default=str(REPO / "config/sinello.toml"))
    parser.add_argument("--input", default="P1")
    parser.add_argument("--output", default="P2")
    args = parser.parse_args()

    model = splinewatch.Model.from_config(args.config)
    print(model)
    modes = model.modes(12)
    bending = [k for k, kind in enumerate(modes["kind"]) if kind == "bending"]
    print("mode   f (Hz)    ζ (%)   largest at")
    for k in bending:
        shape = modes["shapes"][:, k]
        print(f"{k + 1:4d} {modes['frequency'][k]:9.3f} {100 * modes['damping'][k]:7.3f}   "
              f"{model.sensors[int(np.argmax(np.abs(shape)))]}")

    first = modes["frequency"][bending[0]]
    f = np.linspace(0.5 * first, 1.5 * first, 201)
    h = model.frf(f, inputs=[args.input], outputs=[args.output])[0, 0]
    peak = f[np.argmax(np.abs(h))]
    print(f"accelerance {args.output}/{args.input}: peak |H| = {np.abs(h).max():.3e} (m/s²)/N at {peak:.3f} Hz")

    spring = next(name for name in model.parameters if name.endswith(".k2"))
    model.parameters[spring] *= 0.5
    softer = model.modes(12)["frequency"]
    print(f"{spring} halved: " + ", ".join(
        f"{modes['frequency'][k]:.3f} → {softer[k]:.3f} Hz" for k in bending[:4]))


if __name__ == "__main__":
    main()
