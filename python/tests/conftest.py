"""Shared fixtures: the repository, the `splinewatch` CLI the package is
compared with bit for bit, and recordings the CLI simulates."""

import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]


def _cli() -> pathlib.Path:
    explicit = os.environ.get("SPLINEWATCH_BIN")
    if explicit:
        return pathlib.Path(explicit)
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    return target / "debug" / "splinewatch"


@pytest.fixture(scope="session")
def repo() -> pathlib.Path:
    return REPO


@pytest.fixture(scope="session")
def cli():
    """Runs the CLI; returns its stdout (fails the test with stderr when it fails)."""
    binary = _cli()
    if not binary.exists():
        pytest.fail(f"the splinewatch CLI is not built at {binary}: run `cargo build` or set SPLINEWATCH_BIN")

    def run(*args, check=True):
        done = subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True, cwd=REPO)
        if check and done.returncode != 0:
            pytest.fail(f"splinewatch {' '.join(map(str, args))} failed:\n{done.stderr}")
        return done

    return run


@pytest.fixture(scope="session")
def ambient(cli, tmp_path_factory):
    """Five minutes of the bundled deck under ambient excitation (12 channels, 256 Hz)."""
    path = tmp_path_factory.mktemp("ambient") / "ambient.mcap"
    cli("simulate", "--config", "config/sinello-ambient.toml", "--duration", "300", "--excitation", "ambient",
        "--seed", "3", "--out", path)
    return path


@pytest.fixture(scope="session")
def forced(cli, tmp_path_factory):
    """A minute of the bundled deck driven by its shaker at P1."""
    path = tmp_path_factory.mktemp("forced") / "forced.mcap"
    cli("simulate", "--config", "config/sinello.toml", "--duration", "60", "--seed", "3", "--out", path)
    return path
