"""Recordings and results files, read by splinewatch's own readers."""

from __future__ import annotations

import json
import os
import warnings
from collections import defaultdict
from typing import Any, Dict, List, NamedTuple, Optional, Union

import numpy as np

from . import _splinewatch


class Channel(NamedTuple):
    """One channel of a recording on its own sample grid."""

    data: np.ndarray
    """Samples (float64); NaN where no block covered the grid."""
    fs: float
    start: np.datetime64
    """Time of the first sample (UTC, ns)."""
    quantity: str
    unit: str
    missing: int
    """Samples between blocks (NaN in ``data``)."""

    @property
    def time(self) -> np.ndarray:
        """Each sample's time (datetime64[ns])."""
        step = np.timedelta64(int(round(1e9 / self.fs)), "ns")
        return self.start + np.arange(len(self.data)) * step


def read_recording(
    path: Union[str, "os.PathLike[str]"], quantity: Optional[str] = "acceleration"
) -> Dict[Any, Channel]:
    """The channels of a raw-input recording (MCAP) as arrays.

    Undecodable messages are not dropped silently: each raises a
    :class:`UserWarning` naming its topic and error.

    Parameters
    ----------
    path : path
    quantity : {"acceleration", "force"} or None
        The channels of this quantity, keyed by sensor name; ``None``: every
        channel, keyed by ``(name, quantity)`` (a sensor may record a force
        and an acceleration under one name).

    Returns
    -------
    dict of str (or (str, str)) to Channel
    """
    channels, skipped = _splinewatch.read_recording(os.fspath(path))
    for topic, log_time, error in skipped:
        warnings.warn(f"{os.fspath(path)}: skipped a message on {topic} at {log_time} ns: {error}", stacklevel=2)
    out: Dict[Any, Channel] = {}
    for c in channels:
        if quantity is not None and c["quantity"] != quantity:
            continue
        key = c["name"] if quantity is not None else (c["name"], c["quantity"])
        out[key] = Channel(
            data=c["data"],
            fs=c["fs"],
            start=np.datetime64(c["start_ns"], "ns"),
            quantity=c["quantity"],
            unit=c["unit"],
            missing=c["missing"],
        )
    return out


def _time(text: Optional[str]) -> np.datetime64:
    if text is None:
        return np.datetime64("NaT", "ns")
    return np.datetime64(text.rstrip("Z"), "ns")


def _nan(v: Optional[float]) -> float:
    return np.nan if v is None else float(v)


#: The results topics (the application's own list), longest first so that
#: ``oma/modes`` is not taken for ``modes``.
RESULT_TOPICS = sorted(_splinewatch.result_topics(), key=len, reverse=True)


def _split_topic(topic: str):
    """(prefix, suffix) of a results topic; an unknown one splits at its last ``/``."""
    for suffix in RESULT_TOPICS:
        if topic.endswith("/" + suffix):
            return topic[: -len(suffix) - 1], suffix
    prefix, _, suffix = topic.rpartition("/")
    return prefix, suffix


class Results:
    """A results file (MCAP of JSON messages) as arrays.

    Attributes
    ----------
    prefix : str
        The topic prefix (``[structure] name`` unless configured).
    topics : list of str
        Every topic suffix present (``updating/parameters``, ``oma/modes``, ...).
    parameters : dict of str to dict
        Per parameter: ``time`` (datetime64[ns]), ``window`` (int64), ``value``
        and ``std`` (float64, NaN: not identifiable), one entry per update.
    updates : dict of str to ndarray
        Per update: ``time``, ``window``, ``converged``, ``relative_residual``, ``iterations``.
    modes : dict of str to ndarray
        Identified modes (``oma/modes``), one entry per mode and window:
        ``time``, ``window``, ``frequency``, ``damping``, ``frequency_std``,
        ``damping_std``, ``mac`` (with its model mode; NaN when unpaired).
    monitoring : dict of str to ndarray
        ``monitoring/status``: ``time``, ``window``, ``state``, ``t2``,
        ``t2_limit``, ``mewma``, ``mewma_limit``, ``temperature_c``.
    """

    def __init__(self, messages: List[Any]) -> None:
        by_suffix: Dict[str, List[Any]] = defaultdict(list)
        prefixes = set()
        for topic, log_time, text in messages:
            prefix, suffix = _split_topic(topic)
            prefixes.add(prefix)
            by_suffix[suffix].append((log_time, json.loads(text)))
        self.prefix = ",".join(sorted(prefixes))
        self._messages = dict(by_suffix)
        self.topics = sorted(by_suffix)
        self.parameters = self._parameters()
        self.updates = self._updates()
        self.modes = self._modes()
        self.monitoring = self._monitoring()

    def messages(self, topic: str) -> List[Dict[str, Any]]:
        """Every message of a topic (its suffix, e.g. ``"windows"``), as dicts, in file order."""
        return [m for _, m in self._messages.get(topic, [])]

    def frf_fit(self, window: Optional[int] = None) -> Dict[str, Any]:
        """The measured and fitted model FRFs of one updated window (default the last).

        Parameters
        ----------
        window : int, optional
            The window number (``updates["window"]``).

        Returns
        -------
        dict
            ``window``, ``frequency`` (n_lines,), ``pairs`` [(input, output)],
            ``measured`` and ``model`` (complex128, n_pairs × n_lines; ``model``
            None when the file has no model FRFs for that window), ``coherence``
            (n_pairs × n_lines, NaN where not given) and ``quantity``.
        """
        measured = {m["window"]: m for m in self.messages("frf/measured")}
        model = {m["window"]: m for m in self.messages("frf/model")}
        if not measured:
            raise ValueError("no frf/measured message: this results file holds no FRF fit (an output-only config?)")
        if window is None:
            window = max(measured)
        if window not in measured:
            raise ValueError(f"window {window} has no measured FRFs (windows with some: {sorted(measured)})")

        def complex_rows(message):
            return np.array([np.asarray(e["re"]) + 1j * np.asarray(e["im"]) for e in message["frfs"]])

        m = measured[window]
        coherence = [e.get("coherence") or [np.nan] * len(m["frequency_hz"]) for e in m["frfs"]]
        return {
            "window": window,
            "frequency": np.asarray(m["frequency_hz"], dtype=np.float64),
            "pairs": [(e["input"], e["output"]) for e in m["frfs"]],
            "measured": complex_rows(m),
            "model": complex_rows(model[window]) if window in model else None,
            "coherence": np.asarray(coherence, dtype=np.float64),
            "quantity": m.get("quantity"),
        }

    def _parameters(self) -> Dict[str, Dict[str, np.ndarray]]:
        rows: Dict[str, List[Any]] = defaultdict(list)
        for m in self.messages("updating/parameters"):
            for p in m["parameters"]:
                rows[p["name"]].append((_time(m["time"]), m["window"], p["value"], _nan(p.get("std"))))
        return {
            name: {
                "time": np.array([r[0] for r in v], dtype="datetime64[ns]"),
                "window": np.array([r[1] for r in v], dtype=np.int64),
                "value": np.array([r[2] for r in v], dtype=np.float64),
                "std": np.array([r[3] for r in v], dtype=np.float64),
            }
            for name, v in rows.items()
        }

    def _updates(self) -> Dict[str, np.ndarray]:
        ms = self.messages("updating/parameters")
        return {
            "time": np.array([_time(m["time"]) for m in ms], dtype="datetime64[ns]"),
            "window": np.array([m["window"] for m in ms], dtype=np.int64),
            "converged": np.array([m["converged"] for m in ms], dtype=bool),
            "relative_residual": np.array([m["relative_residual"] for m in ms], dtype=np.float64),
            "iterations": np.array([m.get("iterations", -1) for m in ms], dtype=np.int64),
        }

    def _modes(self) -> Dict[str, np.ndarray]:
        rows = [
            (
                _time(m["time"]),
                m["window"],
                mode["frequency_hz"],
                mode["damping_ratio"],
                _nan(mode.get("frequency_std_hz")),
                _nan(mode.get("damping_std")),
                _nan(mode.get("mac")),
            )
            for m in self.messages("oma/modes")
            for mode in m["modes"]
        ]
        names = ["time", "window", "frequency", "damping", "frequency_std", "damping_std", "mac"]
        types = ["datetime64[ns]", np.int64] + [np.float64] * 5
        return {n: np.array([r[k] for r in rows], dtype=t) for k, (n, t) in enumerate(zip(names, types))}

    def _monitoring(self) -> Dict[str, np.ndarray]:
        ms = self.messages("monitoring/status")
        out: Dict[str, np.ndarray] = {
            "time": np.array([_time(m["time"]) for m in ms], dtype="datetime64[ns]"),
            "window": np.array([m["window"] for m in ms], dtype=np.int64),
            "state": np.array([m["state"] for m in ms], dtype=object),
        }
        for key in ["t2", "t2_limit", "mewma", "mewma_limit", "temperature_c"]:
            out[key] = np.array([_nan(m.get(key)) for m in ms], dtype=np.float64)
        return out

    def to_pandas(self) -> Dict[str, Any]:
        """The tables as pandas DataFrames (needs pandas).

        Returns
        -------
        dict
            ``parameters`` (long: time, window, name, value, std), ``updates``,
            ``modes`` and ``monitoring``.
        """
        try:
            import pandas as pd
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("Results.to_pandas needs pandas: pip install pandas") from e
        long = [
            pd.DataFrame({"name": name, **columns}) for name, columns in self.parameters.items()
        ]
        return {
            "parameters": pd.concat(long, ignore_index=True) if long else pd.DataFrame(),
            "updates": pd.DataFrame(self.updates),
            "modes": pd.DataFrame(self.modes),
            "monitoring": pd.DataFrame(self.monitoring),
        }

    def __repr__(self) -> str:
        return f"Results({self.prefix!r}: {len(self.updates['time'])} updates, {len(self.parameters)} parameters, topics {self.topics})"


def read_results(path: Union[str, "os.PathLike[str]"]) -> Results:
    """Reads a results file the daemon, ``replay`` or ``events`` wrote.

    Parameters
    ----------
    path : path
        The results MCAP (JSON messages under ``<prefix>/…``).

    Returns
    -------
    Results
    """
    return Results(_splinewatch.read_results(os.fspath(path)))
