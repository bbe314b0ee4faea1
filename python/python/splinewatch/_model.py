"""A configured B-spline shell model: modes, FRFs, matrices and updating."""

from __future__ import annotations

import json
import os
import tempfile
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _splinewatch
from ._identification import Modes


class Update:
    """The result of :meth:`Model.update` (``splinewatch update --json``).

    Attributes
    ----------
    values : dict of str to float
        The updated parameters.
    std : dict of str to float
        One standard deviation each (NaN: not identifiable).
    bounds : dict of str to (float, float)
    correlations : list of (str, str, float)
        The most correlated parameter pairs, largest ``|rho|`` first.
    held : list of (str, str, float)
        Parameters the data could not inform: name, reason, value.
    iterations : int
        Accepted Levenberg-Marquardt iterations.
    converged : bool
    stop_reason : str
    relative_residual : float
    condition_number : float
    pairs : list of (int, int, float)
        Modal updating only: identified mode, model mode (0-based), MAC.
    """

    def __init__(self, text: str, pairs: Optional[List[Tuple[int, int, float]]] = None) -> None:
        self._text = text
        r = json.loads(text)
        #: The result as ``update --json`` writes it (a dict).
        self.raw: Dict[str, Any] = r
        params = r["parameters"]
        self.values = {p["name"]: p["value"] for p in params}
        self.std = {p["name"]: (np.nan if p["std"] is None else p["std"]) for p in params}
        self.bounds = {p["name"]: (p["lower"], p["upper"]) for p in params}
        self.correlations = [(c["a"], c["b"], c["rho"]) for c in r.get("correlations", [])]
        self.held = [(h["name"], h["reason"], h["value"]) for h in r.get("held", [])]
        self.iterations = max(len(r["iterations"]) - 1, 0)
        self.converged: bool = r["converged"]
        self.stop_reason: str = r["stop_reason"]
        self.relative_residual: float = r["relative_residual"]
        self.condition_number: float = r["condition_number"]
        self.pairs = pairs or []

    def to_json(self) -> str:
        """The result JSON, byte for byte what ``splinewatch update --json`` prints (without its newline)."""
        return self._text

    def __repr__(self) -> str:
        state = "converged" if self.converged else f"stopped ({self.stop_reason})"
        return f"Update({len(self.values)} parameters, {state}, relative residual {self.relative_residual:.4g})"


class Model:
    """A bridge deck's model from a splinewatch config.

    Build it with :meth:`from_config` or :meth:`from_toml`.

    Attributes
    ----------
    parameters : dict of str to float
        The updating parameters (``[updating]``) and their values, the
        config's to start with. Change them freely: :meth:`modes`,
        :meth:`frf` and the start of :meth:`update` use the current values.
    sensors : list of str
        The config's sensors, in order.
    """

    def __init__(self, raw: "_splinewatch.RawModel") -> None:
        self._raw = raw
        self._names: List[str] = raw.parameter_names()
        self.parameters: Dict[str, float] = dict(zip(self._names, raw.base_values().tolist()))
        self.sensors: List[str] = raw.sensors()

    @classmethod
    def from_config(cls, path: Union[str, "os.PathLike[str]"]) -> "Model":
        """Reads and validates a config file (as ``splinewatch check-config``).

        Raises
        ------
        FileNotFoundError
            No such file.
        ValueError
            The config is invalid (the message names the key).
        """
        return cls(_splinewatch.RawModel.from_config(os.fspath(path)))

    @classmethod
    def from_toml(cls, text: str) -> "Model":
        """Builds the model of a config given as TOML text."""
        return cls(_splinewatch.RawModel.from_toml(text))

    @property
    def structure(self) -> str:
        """``[structure] name``."""
        return self._raw.structure()

    @property
    def bounds(self) -> Dict[str, Tuple[float, float]]:
        """Each parameter's (lower, upper) bound."""
        return dict(zip(self._names, self._raw.bounds()))

    def _values(self) -> np.ndarray:
        unknown = set(self.parameters) - set(self._names)
        if unknown:
            raise KeyError(f"unknown parameters {sorted(unknown)} (the model's: {', '.join(self._names)})")
        missing = [n for n in self._names if n not in self.parameters]
        if missing:
            raise KeyError(f"parameters {missing} were removed; every parameter needs a value")
        return np.array([float(self.parameters[n]) for n in self._names], dtype=np.float64)

    def modes(self, n: Optional[int] = None) -> Dict[str, Any]:
        """The first ``n`` modes at the current parameters (default all).

        Returns
        -------
        dict
            ``frequency`` (Hz) and ``damping`` (ζ(f) of the config, plus the
            supports' loss factors' share) of shape (n,), ``kind`` (rigid,
            membrane or bending), ``motion`` (longitudinal, transverse,
            vertical or torsion: where most of the mode's energy goes on the
            deck), ``motion_shares`` of shape (n, 4) (those four shares,
            summing to 1), ``support_shares`` of shape (n, n_supports) (each
            support's share of the mode's strain energy; ``supports`` names
            them: spring fields, bearings, line supports) and ``shapes`` at
            the sensors, shape (n_sensors, n), mass-normalised.
        """
        out = self._raw.modes(self._values(), None if n is None else int(n))
        out["sensors"] = list(self.sensors)
        return out

    def frf(
        self,
        f: Any,
        inputs: Optional[Sequence[str]] = None,
        outputs: Optional[Sequence[str]] = None,
        quantity: str = "accelerance",
    ) -> np.ndarray:
        """Model FRFs at the current parameters (paper eq. 31-32).

        Parameters
        ----------
        f : array_like, shape (n_lines,)
            Frequencies (Hz), positive.
        inputs, outputs : sequence of str, optional
            Sensor names; default every sensor.
        quantity : {"accelerance", "mobility", "receptance"}

        Returns
        -------
        ndarray of complex128, shape (n_outputs, n_inputs, n_lines)
        """
        inputs = list(self.sensors if inputs is None else inputs)
        outputs = list(self.sensors if outputs is None else outputs)
        lines = np.asarray(f, dtype=np.float64).ravel()
        pairs = [(o, i) for o in outputs for i in inputs]
        h = self._raw.frf(self._values(), lines, pairs, quantity)
        return h.reshape(len(outputs), len(inputs), len(lines))

    def matrices(self) -> Dict[str, Any]:
        """The model's matrices at the config's values as ``scipy.sparse``.

        The files of ``splinewatch matrices``, read back: ``K``, ``K_f`` (free
        stiffness, eq. 16), ``M`` (mass, eq. 17), ``dK`` (a dict: each
        parameter's ``∂K/∂p``; ``K = K_f + Σ (θ - 1) ∂K/∂θ + Σ κ ∂K/∂κ``, eq.
        23) and ``index`` (what every row is).
        """
        import scipy.io
        import scipy.sparse

        with tempfile.TemporaryDirectory(prefix="splinewatch-matrices-") as d:
            index = json.loads(self._raw.export_matrices(d))

            def read(name: str) -> "scipy.sparse.csr_matrix":
                return scipy.sparse.csr_matrix(scipy.io.mmread(os.path.join(d, name)))

            return {
                "K": read(index["stiffness"]),
                "K_f": read(index["free_stiffness"]),
                "M": read(index["mass"]),
                "dK": {p["name"]: read(p["file"]) for p in index["parameters"]},
                "index": index,
            }

    def synthetic_frf(
        self,
        inputs: Sequence[str],
        outputs: Sequence[str],
        f_min: float,
        f_max: float,
        step: float,
        *,
        noise: float = 0.0,
        seed: int = 1,
        quantity: str = "accelerance",
    ) -> str:
        """Model FRFs at the config's values with complex noise, as FRF JSON (``splinewatch synth``).

        ``noise`` is the noise's standard deviation as a fraction of each FRF's RMS.
        """
        return self._raw.synth(
            list(inputs), list(outputs), float(f_min), float(f_max), float(step), float(noise), int(seed), quantity
        )

    def update(
        self,
        *,
        frf: Optional[Union[str, bytes, "os.PathLike[str]"]] = None,
        modes: Optional[Union[Modes, str, "os.PathLike[str]"]] = None,
        apply: bool = True,
    ) -> Update:
        """Updates the parameters by bounded Levenberg-Marquardt (``splinewatch update``).

        Starts from the current :attr:`parameters` (warm start). Give exactly
        one of:

        Parameters
        ----------
        frf : path, str or bytes
            Measured FRFs: an FRF JSON or universal file (path, or its
            content). FRF residues (eq. 36-39).
        modes : Modes, path or str
            Identified modes (:func:`oma`, :func:`identify`, or a modes
            file / its JSON). Modal residues.
        apply : bool
            Set :attr:`parameters` to the updated values.

        Returns
        -------
        Update
        """
        if (frf is None) == (modes is None):
            raise ValueError("give frf=... or modes=... (one of them)")
        values = self._values()
        if frf is not None:
            content = _content(frf, binary=True)
            update = Update(self._raw.update_frf(content, values))
        else:
            text = modes.to_json() if isinstance(modes, Modes) else _content(modes, binary=False)
            result, pairs = self._raw.update_modes(text, values)
            update = Update(result, pairs)
        if apply:
            self.parameters = dict(update.values)
        return update

    def __repr__(self) -> str:
        return f"Model({self.structure!r}, {len(self._names)} parameters, {len(self.sensors)} sensors)"


def _content(source: Any, binary: bool) -> Any:
    """A file's content, or the content itself when ``source`` already is one."""
    if isinstance(source, bytes):
        return source if binary else source.decode("utf-8")
    if isinstance(source, str) and source.lstrip().startswith(("{", "-1", "    -1")):
        return source.encode("utf-8") if binary else source
    path = os.fspath(source)
    if not os.path.exists(path):
        raise FileNotFoundError(f"cannot read {path}: no such file")
    with open(path, "rb") as f:
        data = f.read()
    return data if binary else data.decode("utf-8")
