"""Output-only modal analysis of a recording, as `splinewatch oma` does it.

    python oma_of_a_recording.py RECORDING.mcap [--band 0.5 80] [--plot diagram.png]

Reads the acceleration channels of a raw-input recording, identifies the
modes by SSI-cov with their standard deviations, prints them, and (with
matplotlib) draws the stabilisation diagram.
"""

import argparse

import numpy as np

import splinewatch


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("recording")
    parser.add_argument("--band", nargs=2, type=float, default=(0.5, 80.0))
    parser.add_argument("--plot", help="write the stabilisation diagram to this image (needs matplotlib)")
    args = parser.parse_args()

    channels = splinewatch.read_recording(args.recording)
    names = sorted(channels, key=lambda n: (len(n), n))
    fs = channels[names[0]].fs
    # Samples × channels, each channel contiguous (Fortran order): read in place.
    data = np.asfortranarray(np.column_stack([channels[n].data for n in names]))
    modes = splinewatch.oma(data, fs, band=tuple(args.band), sensors=names, start=channels[names[0]].start)

    print(f"{len(modes)} modes from {data.shape[0] / fs:.0f} s of {len(names)} channels at {fs:g} Hz")
    print("  f (Hz)     σ_f (Hz)    ζ (%)    σ_ζ (%)   MPC")
    for k in range(len(modes)):
        print(f"{modes.frequency[k]:9.4f}  {modes.frequency_std[k]:9.5f}  {100 * modes.damping[k]:7.3f}  "
              f"{100 * modes.damping_std[k]:8.4f}  {modes.mpc[k]:5.3f}")

    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        diagram = modes.stabilisation
        fig, ax = plt.subplots(figsize=(8, 5))
        stable = diagram["stable"]
        ax.plot(diagram["frequency"][~stable], diagram["order"][~stable], ".", color="0.75", ms=3, label="pole")
        ax.plot(diagram["frequency"][stable], diagram["order"][stable], ".", color="C0", ms=4, label="stable")
        for f in modes.frequency:
            ax.axvline(f, color="C3", lw=0.6)
        ax.set(xlabel="frequency (Hz)", ylabel="model order", title="Stabilisation diagram (SSI-cov)")
        ax.legend(loc="lower right")
        fig.savefig(args.plot, dpi=120, bbox_inches="tight")
        print(f"wrote {args.plot}")


if __name__ == "__main__":
    main()
