"""splinewatch: vibration-based monitoring of bridges, from Python.

Identification (output-only SSI-cov and input-output SRIM, with
uncertainty), Welch FRFs, B-spline (isogeometric) shell models of a deck
from a splinewatch config (modes, FRFs, matrices, updating), and the
recordings and results files the daemon writes: numpy in and out. The
engine is splinewatch's Rust core (the CLI's, bit for bit).

>>> import numpy as np, splinewatch
>>> modes = splinewatch.oma(data, fs=100.0)          # doctest: +SKIP
>>> model = splinewatch.Model.from_config("config/sinello.toml")  # doctest: +SKIP
>>> model.update(modes=modes)                         # doctest: +SKIP
"""

from ._splinewatch import __version__
from ._files import Channel, Results, read_recording, read_results
from ._identification import FittedModes, Modes, fit_modes, frf, identify, oma
from ._model import Model, Update

__all__ = [
    "__version__",
    "Channel",
    "FittedModes",
    "Model",
    "Modes",
    "Results",
    "Update",
    "fit_modes",
    "frf",
    "identify",
    "oma",
    "read_recording",
    "read_results",
]
