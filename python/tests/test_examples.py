"""Every example in python/examples runs to the end on the bundled data."""

import subprocess
import sys

import pytest


GALLERY = "docs/guide/src/images/gallery"


def _shown(repo, name):
    """What the guide's gallery shows the example printing (docs/guide/make_gallery.sh)."""
    return (repo / GALLERY / name).read_text()


def _printed(out):
    """An example's output without the line naming the figure it wrote."""
    return "".join(line + "\n" for line in out.splitlines() if not line.startswith("wrote "))


def _run(repo, name, *args):
    done = subprocess.run([sys.executable, str(repo / "python/examples" / name), *map(str, args)],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_oma_of_a_recording(repo, ambient, tmp_path):
    pytest.importorskip("matplotlib", reason="the --plot part needs matplotlib (pip install splinewatch[plot])")
    out = _run(repo, "oma_of_a_recording.py", ambient, "--plot", tmp_path / "diagram.png")
    assert "modes from 300 s of 12 channels at 256 Hz" in out
    assert (tmp_path / "diagram.png").stat().st_size > 10_000


def test_model_modes_and_frfs(repo):
    out = _run(repo, "model_modes_and_frfs.py")
    assert "accelerance P2/P1" in out and "halved" in out
    assert out == _shown(repo, "model_modes_and_frfs.txt"), "the gallery shows another output"


def test_update_from_synthetic_frfs(repo):
    out = _run(repo, "update_from_synthetic_frfs.py")
    assert "converged" in out and "west.k1" in out
    assert out == _shown(repo, "update_from_synthetic_frfs.txt"), "the gallery shows another output"


def test_the_gallery_shows_what_the_examples_print_on_the_bundled_recording(cli, repo, tmp_path):
    recording = repo / "recordings/sinello-demo.mcap"
    out = _run(repo, "oma_of_a_recording.py", recording)
    assert _printed(out) == _shown(repo, "oma_of_a_recording.txt")
    results = tmp_path / "results.mcap"
    cli("replay", "--config", "config/sinello.toml", recording, "--out", results)
    out = _run(repo, "plot_results_trends.py", results)
    assert _printed(out) == _shown(repo, "plot_results_trends.txt")


def test_plot_results_trends(cli, repo, forced, tmp_path):
    pytest.importorskip("matplotlib", reason="the --save part needs matplotlib (pip install splinewatch[plot])")
    results = tmp_path / "results.mcap"
    cli("replay", "--config", "config/sinello.toml", forced, "--out", results)
    out = _run(repo, "plot_results_trends.py", results, "--save", tmp_path / "trends.png")
    assert "west.k1" in out and (tmp_path / "trends.png").stat().st_size > 10_000
