"""The guide's figures, remade from the bundled data by the Python package
and matplotlib (SVG, so they diff and scale):

- deck-<config>.svg: each bundled deck from above at an angle (its control
  net, patch by patch) and a section view, the sensors and bearings labelled;
- mode-sinello.svg: the Sinello span's first bending modes (eigsh on the
  model's own K and M);
- stabilisation-sinello.svg: SSI-cov's stabilisation diagram of the bundled
  recording's accelerations;
- frf-fit-sinello.svg: measured FRFs of the bundled recording and the model's
  after updating on them;
- trend-alarm-sinello.svg: two weeks of hourly windows with a bearing losing
  stiffness (config/scenarios/two-weeks-bearing-loss.toml): east.k2 ± 2σ and
  the monitoring state, the alarm shaded (needs the CLI: --splinewatch).

    python docs/guide/make_figures.py [--splinewatch target/debug/splinewatch]

in a venv with the package (pip install ./python), matplotlib and scipy.
"""

import argparse
import pathlib
import subprocess
import tempfile
import tomllib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import scipy.sparse.linalg  # noqa: E402

import splinewatch  # noqa: E402

REPO = pathlib.Path(__file__).resolve().parents[2]
OUT = REPO / "docs/guide/src/images"
plt.rcParams.update({"svg.hashsalt": "splinewatch", "font.size": 9})  # reproducible SVG ids


def control_nets(model):
    """Per patch, the control points' positions on their (i, j) net."""
    index = model.matrices()["index"]
    nets = {}
    for dof in index["dofs"]:
        nets.setdefault(dof["patch"], {})[tuple(dof["net_index"])] = dof["position"]
    return index, nets


def draw_net(ax, net, colour, project=lambda p: p, lw=0.6):
    imax = max(i for i, _ in net) + 1
    jmax = max(j for _, j in net) + 1
    for i in range(imax):
        line = [project(net[(i, j)]) for j in range(jmax) if (i, j) in net]
        ax.plot(*zip(*line), color=colour, lw=lw)
    for j in range(jmax):
        line = [project(net[(i, j)]) for i in range(imax) if (i, j) in net]
        ax.plot(*zip(*line), color=colour, lw=lw)


def deck_figure(name):
    path = REPO / f"config/{name}.toml"
    config = tomllib.loads(path.read_text())
    model = splinewatch.Model.from_config(path)
    _, nets = control_nets(model)
    sensors = [s for s in config.get("sensors", []) if "x" in s]
    bearings = config.get("model", {}).get("bearings", [])
    fig = plt.figure(figsize=(10, 7))
    grid = fig.add_gridspec(2, 1, height_ratios=[3, 1])
    ax = fig.add_subplot(grid[0], projection="3d")
    colours = plt.cm.tab10.colors
    for k, (patch, net) in enumerate(sorted(nets.items())):
        draw_net(ax, net, colours[k % 10])
    for s in sensors:
        ax.scatter(s["x"], s["y"], s.get("z", 0.0), color="k", s=12, depthshade=False)
        ax.text(s["x"], s["y"], s.get("z", 0.0), " " + s["name"], fontsize=6)
    for b in bearings:
        ax.scatter(*b["at"], marker="^", color="C3", s=30, depthshade=False)
        ax.text(*b["at"], " " + b["name"], fontsize=6, color="C3")
    points = np.array([p for net in nets.values() for p in net.values()])
    lo, hi = points.min(axis=0), points.max(axis=0)
    span = hi - lo
    # Width and depth drawn at least a third and a sixth of the length (not to scale).
    ax.set_box_aspect((span[0], max(span[1], span[0] / 3), max(span[2], span[0] / 6)), zoom=1.5)
    ax.set_zticks([round(lo[2], 2), round(hi[2], 2)] if span[2] > 0 else [lo[2]])
    ax.view_init(elev=35, azim=-60)
    ax.set(xlabel="x (m)", ylabel="y (m)", zlabel="z (m)",
           title=f"{model.structure}: control net from above (width and depth stretched)")
    # Section: the control points near mid-length, seen along x.
    sec = fig.add_subplot(grid[1])
    mid = 0.5 * (points[:, 0].min() + points[:, 0].max())
    for k, (patch, net) in enumerate(sorted(nets.items())):
        imax = max(i for i, _ in net) + 1
        i_mid = min(range(imax), key=lambda i: np.mean([abs(p[0] - mid) for (ii, _), p in net.items() if ii == i]))
        line = [net[(i_mid, j)] for j in range(max(j for _, j in net) + 1) if (i_mid, j) in net]
        sec.plot([p[1] for p in line], [p[2] for p in line], "-o", ms=2, color=colours[k % 10], label=patch)
    for b in bearings:
        sec.plot(b["at"][1], b["at"][2], "^", color="C3", ms=6)
    sec.set(xlabel="y (m)", ylabel="z (m)", title=f"section near x = {mid:.1f} m", aspect="equal")
    if span[2] < 0.5:  # a flat deck: its thickness is the shell's, not drawn
        sec.set_ylim(-1.0, 1.0)
    if len(nets) > 1:
        sec.legend(fontsize=6, loc="center left", bbox_to_anchor=(1.01, 0.5))
    fig.subplots_adjust(left=0.06, right=0.85, top=0.97, bottom=0.08, hspace=0.05)
    fig.savefig(OUT / f"deck-{pathlib.Path(name).name}.svg")
    plt.close(fig)


def mode_figure():
    model = splinewatch.Model.from_config(REPO / "config/sinello.toml")
    mats = model.matrices()
    k, m, index = mats["K"].tocsc(), mats["M"].tocsc(), mats["index"]
    values, vectors = scipy.sparse.linalg.eigsh(k, k=8, M=m, sigma=(2 * np.pi * 5.0) ** 2)
    order = np.argsort(values)
    rows = {}
    for dof in index["dofs"]:
        for c in dof["components"]:
            if c["dof"] == "w":
                rows[dof["row"] - 1] = (tuple(dof["net_index"]), dof["position"], c["weight"])
    fig = plt.figure(figsize=(10, 5))
    shown = 0
    for n in order:
        f = np.sqrt(abs(values[n])) / (2 * np.pi)
        if f < 1.0 or shown == 4:
            continue
        w = {net: (pos, weight * vectors[row, n]) for row, (net, pos, weight) in rows.items()}
        scale = 1.5 / max(abs(v) for _, v in w.values())
        net = {key: (pos[0], pos[1], pos[2] + scale * v) for key, (pos, v) in w.items()}
        ax = fig.add_subplot(2, 2, shown + 1, projection="3d")
        draw_net(ax, net, "C0", lw=0.8)
        ax.set_box_aspect((16, 9, 4))
        ax.view_init(elev=30, azim=-60)
        ax.set_axis_off()
        ax.set_title(f"{f:.2f} Hz", fontsize=9)
        shown += 1
    fig.suptitle("Sinello span: the first bending modes (vertical control-point displacements)")
    fig.tight_layout()
    fig.savefig(OUT / "mode-sinello.svg")
    plt.close(fig)


def demo_recording():
    path = REPO / "recordings/sinello-demo.mcap"
    accelerations = splinewatch.read_recording(path)
    force = splinewatch.read_recording(path, quantity="force")["P1"]
    names = [f"P{k}" for k in range(1, 13)]
    return force, names, np.column_stack([accelerations[n].data for n in names])


def stabilisation_figure():
    force, names, data = demo_recording()
    modes = splinewatch.oma(np.asfortranarray(data), force.fs, band=(0.5, 80.0), sensors=names)
    d = modes.stabilisation
    fig, ax = plt.subplots(figsize=(8, 4.5))
    stable = d["stable"]
    ax.plot(d["frequency"][~stable], d["order"][~stable], ".", color="0.8", ms=2, label="pole")
    ax.plot(d["frequency"][stable], d["order"][stable], ".", color="C0", ms=3, label="stable")
    ax.plot(d["frequency"][d["mode"] >= 0], d["order"][d["mode"] >= 0], ".", color="C1", ms=3, label="in a mode")
    for f, s in zip(modes.frequency, modes.frequency_std):
        ax.axvspan(f - 2 * s, f + 2 * s, color="C3", alpha=0.3, lw=0)
    ax.set(xlim=(0, 80), xlabel="frequency (Hz)", ylabel="model order",
           title=f"SSI-cov of the bundled recording: {len(modes)} modes (red: ±2σ)")
    ax.legend(loc="lower right", fontsize=7)
    fig.tight_layout()
    fig.savefig(OUT / "stabilisation-sinello.svg")
    plt.close(fig)


def frf_fit_figure():
    force, names, data = demo_recording()
    f, h, coherence = splinewatch.frf(force.data, data, force.fs, segment_seconds=4.0, band=(0.5, 80.0))
    measured = {
        "quantity": "accelerance",
        "frequency_hz": f.tolist(),
        "frfs": [{"input": "P1", "output": n, "re": h[k].real.tolist(), "im": h[k].imag.tolist(),
                  "coherence": np.clip(coherence[k], 0, 1).tolist()} for k, n in enumerate(names)],
    }
    import json

    model = splinewatch.Model.from_config(REPO / "config/sinello.toml")
    before = model.frf(f, inputs=["P1"], outputs=["P2", "P8"])[:, 0]
    update = model.update(frf=json.dumps(measured))
    after = model.frf(f, inputs=["P1"], outputs=["P2", "P8"])[:, 0]
    fig, axes = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    for ax, k, name in zip(axes, (1, 7), ("P2", "P8")):
        row = 0 if name == "P2" else 1
        ax.semilogy(f, abs(h[k]), color="0.3", lw=0.8, label="measured (Welch H1)")
        ax.semilogy(f, abs(before[row]), color="C1", lw=0.8, ls="--", label="model, config's values")
        ax.semilogy(f, abs(after[row]), color="C0", lw=0.9, label="model, updated")
        ax.set_ylabel(f"|H| {name}/P1 ((m/s²)/N)")
    axes[0].legend(fontsize=7)
    axes[1].set_xlabel("frequency (Hz)")
    fig.suptitle(f"FRF fit on the bundled recording: relative residual {update.relative_residual:.3f}")
    fig.tight_layout()
    fig.savefig(OUT / "frf-fit-sinello.svg")
    plt.close(fig)


def trend_figure(binary):
    with tempfile.TemporaryDirectory() as d:
        frf, results = pathlib.Path(d) / "frf.mcap", pathlib.Path(d) / "results.mcap"
        config = REPO / "config/sinello-monitoring.toml"
        subprocess.run([binary, "simulate", "--config", config, "--scenario",
                        REPO / "config/scenarios/two-weeks-bearing-loss.toml", "--frf-windows", "336",
                        "--out", frf], check=True, capture_output=True)
        subprocess.run([binary, "replay", "--config", config, frf, "--out", results], check=True,
                       capture_output=True)
        r = splinewatch.read_results(results)
    p = r.parameters["east.k2"]
    mon = r.monitoring
    fig, (a, b) = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    a.plot(p["time"], p["value"], ".", ms=2, color="C0")
    a.fill_between(p["time"], p["value"] - 2 * p["std"], p["value"] + 2 * p["std"], color="C0", alpha=0.25, lw=0)
    a.set_ylabel("east.k2 (N/m³)")
    b.semilogy(mon["time"], mon["t2"], ".", ms=2, color="C0", label="T²")
    b.semilogy(mon["time"], mon["t2_limit"], color="C3", lw=0.8, label="limit")
    alarm = mon["state"] == "alarm"
    for ax in (a, b):
        for t in mon["time"][alarm]:
            ax.axvspan(t, t + np.timedelta64(1, "h"), color="C3", alpha=0.15, lw=0)
    b.set_ylabel("Hotelling T²")
    b.legend(fontsize=7)
    fig.suptitle("Two weeks of hourly windows, a bearing losing stiffness from window 200 (red: alarm)")
    fig.autofmt_xdate()
    fig.tight_layout()
    fig.savefig(OUT / "trend-alarm-sinello.svg")
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--splinewatch", default=str(REPO / "target/debug/splinewatch"))
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    for name in ("sinello", "overpass", "painter-street", "examples/slab-on-web"):
        deck_figure(name)
    mode_figure()
    stabilisation_figure()
    frf_fit_figure()
    trend_figure(args.splinewatch)
    print(f"wrote the figures to {OUT}")


if __name__ == "__main__":
    main()
