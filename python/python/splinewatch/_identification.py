"""Identification from arrays: output-only SSI-cov, input-output SRIM and Welch FRFs."""

from __future__ import annotations

import json
from typing import Any, Dict, Mapping, Optional, Sequence, Tuple

import numpy as np

from . import _splinewatch


class Modes:
    """Identified modes with their uncertainty.

    Returned by :func:`oma` and :func:`identify`; every array has one entry
    (row) per mode, in ascending frequency.

    Attributes
    ----------
    frequency, damping : ndarray of float64, shape (n_modes,)
        Natural frequency (Hz) and damping ratio.
    frequency_std, damping_std : ndarray of float64, shape (n_modes,)
        Their standard deviations (delete-one-batch replicates); NaN where
        fewer than two replicates found the mode.
    shapes : ndarray of complex128, shape (n_modes, n_channels)
        Mode shapes at the output channels, largest component ``1 + 0j``.
    shapes_std : ndarray of float64, shape (n_modes, n_channels)
        Standard deviation of each shape component (NaN: not estimated).
    mpc : ndarray of float64, shape (n_modes,)
        Modal phase collinearity.
    order, stable_orders : ndarray of int64, shape (n_modes,)
        Model order of the reported pole and how many orders the mode was
        stable at.
    sensors : list of str
        The output channels' names (``ch1``, ``ch2``, ... unless given).
    """

    def __init__(self, raw: "_splinewatch.RawModes") -> None:
        self._raw = raw
        c = raw.columns()
        self.frequency: np.ndarray = c["frequency"]
        self.damping: np.ndarray = c["damping"]
        self.frequency_std: np.ndarray = c["frequency_std"]
        self.damping_std: np.ndarray = c["damping_std"]
        self.shapes: np.ndarray = c["shapes"]
        self.shapes_std: np.ndarray = c["shapes_std"]
        self.mpc: np.ndarray = c["mpc"]
        self.order: np.ndarray = c["order"]
        self.stable_orders: np.ndarray = c["stable_orders"]
        self.sensors: list = c["sensors"]
        self.fs: float = c["fs"]
        self.samples: int = c["samples"]
        #: Whether the data had to be copied (not Fortran-ordered).
        self.copied: bool = c["copied"]

    def __len__(self) -> int:
        return len(self.frequency)

    def __repr__(self) -> str:
        rows = ", ".join(f"{f:.3f} Hz" for f in self.frequency)
        return f"Modes({len(self)} modes: {rows})"

    @property
    def stabilisation(self) -> Dict[str, np.ndarray]:
        """The stabilisation diagram.

        Returns
        -------
        dict
            ``order``, ``frequency``, ``damping``, ``stable`` (bool) and
            ``mode`` (index into the modes, -1 for none) of every pole, and
            ``singular_values`` of the subspace matrix.
        """
        return self._raw.diagram()

    def to_json(self, path: Optional[str] = None) -> str:
        """The modes file ``splinewatch update --modes`` reads.

        Parameters
        ----------
        path : str, optional
            Also write it there.

        Returns
        -------
        str
            The JSON text, byte for byte what ``splinewatch oma --json`` writes
            for the same modes.
        """
        text = self._raw.to_json()
        if path is not None:
            with open(path, "w", encoding="utf-8") as f:
                f.write(text)
        return text


def _orders(orders: Sequence[int]) -> Dict[str, int]:
    if len(orders) not in (2, 3):
        raise ValueError(f"orders must be (min, max) or (min, max, step), got {tuple(orders)!r}")
    keys = {"min_order": int(orders[0]), "max_order": int(orders[1])}
    if len(orders) == 3:
        keys["order_step"] = int(orders[2])
    return keys


def _settings(
    band: Optional[Tuple[float, float]],
    block_rows: int,
    orders: Sequence[int],
    batches: int,
    uncertainty: str,
    stability: Optional[Mapping[str, Any]],
    clustering: Optional[Mapping[str, Any]],
) -> str:
    settings: Dict[str, Any] = {
        "block_rows": int(block_rows),
        "batches": int(batches),
        "uncertainty": uncertainty,
        **_orders(orders),
    }
    if band is not None:
        settings["band"] = [float(band[0]), float(band[1])]
    if stability:
        settings["stability"] = dict(stability)
    if clustering:
        settings["clustering"] = dict(clustering)
    return json.dumps(settings)


def _ns(start: Any) -> Optional[int]:
    """A first-sample time as ns since the Unix epoch."""
    if start is None:
        return None
    if isinstance(start, (int, np.integer)):
        return int(start)
    return int(np.datetime64(start, "ns").astype(np.int64))


def _matrix(data: Any, name: str) -> np.ndarray:
    a = np.asarray(data, dtype=np.float64)
    if a.ndim == 1:
        a = a[:, None]
    if a.ndim != 2:
        raise ValueError(f"{name} must be samples × channels (2-D), got {a.ndim} dimensions")
    return a


def oma(
    data: Any,
    fs: float,
    *,
    band: Optional[Tuple[float, float]] = None,
    block_rows: int = 40,
    orders: Sequence[int] = (2, 120, 2),
    batches: int = 16,
    uncertainty: str = "first_order",
    references: Optional[Sequence[int]] = None,
    sensors: Optional[Sequence[str]] = None,
    stability: Optional[Mapping[str, Any]] = None,
    clustering: Optional[Mapping[str, Any]] = None,
    start: Any = None,
) -> Modes:
    """Output-only modes by covariance-driven SSI with uncertainty.

    The method of ``splinewatch oma`` and the daemon's output-only windows
    (Peeters & De Roeck 1999; uncertainty by delete-one-batch replicates,
    first order after Reynders et al. 2008, or exact jackknife).

    Parameters
    ----------
    data : array_like, shape (n_samples, n_channels)
        Output accelerations, as pyOMA2 and KOMA take them. A
        Fortran-ordered array (``x.T`` of a channels × samples array) is
        read in place; any other layout is copied once.
    fs : float
        Sampling frequency (Hz).
    band : (float, float), optional
        Band of the reported modes (Hz); default 0 to fs/2.
    block_rows : int
        ``p``: the block Hankel matrix has ``p + 1`` block rows (``[oma] block_rows``).
    orders : (min, max) or (min, max, step)
        Model orders of the stabilisation diagram.
    batches : int
        Correlation batches of the uncertainty (>= 2).
    uncertainty : {"first_order", "jackknife"}
        How each replicate's poles are obtained.
    references : sequence of int, optional
        Reference channels (columns); default every channel.
    sensors : sequence of str, optional
        Channel names for the shapes and the modes file.
    stability, clustering : dict, optional
        ``[oma.stability]`` and ``[oma.clustering]`` keys (e.g.
        ``{"frequency": 0.01, "min_mpc": 0.7}``).
    start : numpy.datetime64 or int, optional
        Time of the first sample (an int: ns since the Unix epoch); written
        to the modes file.

    Returns
    -------
    Modes

    Raises
    ------
    ValueError
        Wrong shape, a non-finite sample, ``fs <= 0``, an unknown or invalid
        setting, or no stable mode (the message says which).
    """
    a = _matrix(data, "data")
    settings = _settings(band, block_rows, orders, batches, uncertainty, stability, clustering)
    refs = list(range(a.shape[1])) if references is None else [int(r) for r in references]
    names = None if sensors is None else list(sensors)
    return Modes(_splinewatch.oma(a, float(fs), settings, refs, names, _ns(start)))


def identify(
    inputs: Any,
    outputs: Any,
    fs: float,
    *,
    band: Optional[Tuple[float, float]] = None,
    horizon: int = 40,
    orders: Sequence[int] = (2, 60, 2),
    batches: int = 8,
    uncertainty: str = "jackknife",
    sensors: Optional[Sequence[str]] = None,
    stability: Optional[Mapping[str, Any]] = None,
    clustering: Optional[Mapping[str, Any]] = None,
    start: Any = None,
) -> Modes:
    """Input-output modes of a record with measured inputs, by SRIM.

    The method of ``splinewatch identify`` (Juang 1997's system realization
    using information matrices, with the stabilisation, clustering and
    delete-one-batch uncertainty of :func:`oma`): suits short transient
    records with several inputs, e.g. an earthquake's ground channels.

    Parameters
    ----------
    inputs : array_like, shape (n_samples, n_inputs)
        Measured inputs (ground accelerations, or a force).
    outputs : array_like, shape (n_samples, n_outputs)
        Responses on the same time grid.
    fs : float
        Sampling frequency (Hz).
    horizon : int
        Prediction horizon (``[oma] block_rows``).
    band, orders, batches, uncertainty, sensors, stability, clustering, start
        As :func:`oma` (default uncertainty: exact jackknife, as
        ``splinewatch identify`` uses).

    Returns
    -------
    Modes
    """
    u = _matrix(inputs, "inputs")
    y = _matrix(outputs, "outputs")
    settings = _settings(band, horizon, orders, batches, uncertainty, stability, clustering)
    names = None if sensors is None else list(sensors)
    return Modes(_splinewatch.identify(u, y, float(fs), settings, names, _ns(start)))


def frf(
    force: Any,
    responses: Any,
    fs: float,
    *,
    segment_seconds: float = 8.0,
    overlap: float = 0.5,
    window: str = "hann",
    estimator: str = "h1",
    detrend: str = "constant",
    averaging: str = "linear",
    band: Optional[Tuple[float, float]] = None,
    return_info: bool = False,
    **frf_keys: Any,
) -> Tuple[np.ndarray, ...]:
    """Welch FRF estimates of responses per force.

    The estimator of ``splinewatch frf`` and the daemon (``[frf]`` section).

    Parameters
    ----------
    force : array_like, shape (n_samples,)
        The measured input.
    responses : array_like, shape (n_samples, n_outputs)
        The responses on the same grid.
    fs : float
        Sampling frequency (Hz).
    segment_seconds, overlap, window, estimator, detrend, averaging
        As the ``[frf]`` keys of the same names (``window``: rectangular,
        hann, hamming, blackman, flattop or impact; ``estimator``: h1, h2
        or hv).
    band : (float, float), optional
        Keep only the lines in this band (Hz); default every line.
    return_info : bool
        Also return a dict of the segments accepted and rejected and the
        effective number of averages (``effective_averages``, what
        :func:`fit_modes` weighs the lines by).
    **frf_keys
        Other ``[frf]`` keys (``force_window_width``, ``exponential_end``,
        ``exponential_weight``, ``full_scale``, ``double_impact_fraction``).

    Returns
    -------
    f : ndarray of float64, shape (n_lines,)
    H : ndarray of complex128, shape (n_outputs, n_lines)
    coherence : ndarray of float64, shape (n_outputs, n_lines)
    info : dict
        Only with ``return_info``.
    """
    x = _matrix(responses, "responses")
    u = np.asarray(force, dtype=np.float64)
    if u.ndim != 1:
        raise ValueError(f"force must be one channel (1-D), got {u.ndim} dimensions")
    keys = dict(
        segment_seconds=float(segment_seconds),
        overlap=float(overlap),
        window=window,
        estimator=estimator,
        detrend=detrend,
        averaging=averaging,
        # the daemon's analysis window must hold one segment; irrelevant here
        window_seconds=max(float(segment_seconds), 1.0),
        **frf_keys,
    )
    f, h, coherence, info = _splinewatch.frf(u, x, float(fs), json.dumps(keys))
    if band is not None:
        keep = (f >= band[0]) & (f <= band[1])
        f, h, coherence = f[keep], h[:, keep], coherence[:, keep]
    return (f, h, coherence, info) if return_info else (f, h, coherence)


class FittedModes:
    """Modes fitted to frequency response functions, with their uncertainty.

    Returned by :func:`fit_modes`; every array has one entry (row) per mode,
    in ascending frequency.

    Attributes
    ----------
    frequency, damping : ndarray of float64, shape (n_modes,)
        Natural frequency (Hz) and damping ratio.
    frequency_std, damping_std : ndarray of float64, shape (n_modes,)
        Their standard deviations: the Gauss-Newton covariance of the whole
        fit, scaled by ``residual_scale``.
    residues : ndarray of complex128, shape (n_modes, n_functions)
        Each mode's residue in each function.
    at_bound : ndarray of bool, shape (n_modes,)
        Whether the fit stopped at the band's edge or a damping bound
        (1e-4, 0.7): the band does not hold that mode.
    residual_scale : float
        The weighted residual sum of squares over its degrees of freedom
        (about 1 when the weights are the lines' standard deviations and
        the model holds).
    iterations : int
        Levenberg-Marquardt iterations, over all modes.
    """

    def __init__(self, raw: Dict[str, Any]) -> None:
        self.frequency: np.ndarray = raw["frequency"]
        self.damping: np.ndarray = raw["damping"]
        self.frequency_std: np.ndarray = raw["frequency_std"]
        self.damping_std: np.ndarray = raw["damping_std"]
        self.residues: np.ndarray = raw["residues"]
        self.at_bound: np.ndarray = np.asarray(raw["at_bound"], dtype=bool)
        self.residual_scale: float = raw["residual_scale"]
        self.iterations: int = raw["iterations"]

    def __len__(self) -> int:
        return len(self.frequency)

    def __repr__(self) -> str:
        modes = ", ".join(
            f"{f:.3f} Hz ± {sf:.3f}, ζ {z:.3f} ± {sz:.3f}{' (at a bound)' if b else ''}"
            for f, sf, z, sz, b in zip(
                self.frequency, self.frequency_std, self.damping, self.damping_std, self.at_bound
            )
        )
        return f"FittedModes({modes})"


def fit_modes(
    f: Any,
    H: Any,
    sigma: Any = None,
    *,
    modes: int = 2,
    coherence: Any = None,
    averages: Optional[int] = None,
    inputs: int = 1,
) -> FittedModes:
    """Modes shared by several frequency response functions, by a weighted fit.

    The frequency-domain estimate of ``splinewatch identify``
    (``[oma.frequency_domain]``): a pole-residue model (the modes' poles
    shared by every function; each function's own residues and complex
    constant) fitted to ``H`` over the band of ``f`` by weighted least
    squares, each line weighted by its standard deviation: the
    maximum-likelihood estimate when those are the estimate's errors. It
    holds modes damped 10-30 % that a subspace method's stabilisation
    misses.

    Parameters
    ----------
    f : array_like, shape (n_lines,)
        Frequencies (Hz), increasing: the band fitted.
    H : array_like of complex, shape (n_functions, n_lines)
        The functions (e.g. H1 transmissibilities from :func:`frf`).
    sigma : array_like, shape (n_functions, n_lines), optional
        Each line's standard deviation. Without it, give ``coherence`` and
        ``averages``: an H1 estimate's ``|H| sqrt((1 - g)/(2 n g))``, ``g``
        the coherence, ``n`` the averages less the inputs (the CLI's
        weights).
    modes : int
        How many modes to fit (found one at a time from a grid over the
        band, then refined together).
    coherence : array_like, shape (n_functions, n_lines), optional
    averages : int, optional
        Welch averages (``frf(..., return_info=True)``'s
        ``effective_averages``).
    inputs : int
        Inputs of the estimate (1 for :func:`frf`).

    Returns
    -------
    FittedModes
    """
    freqs = np.ascontiguousarray(f, dtype=np.float64)
    if freqs.ndim != 1:
        raise ValueError(f"f must be 1-D (the lines), got {freqs.ndim} dimensions")
    h = np.ascontiguousarray(np.atleast_2d(H), dtype=np.complex128)
    if sigma is None:
        if coherence is None or averages is None:
            raise ValueError("give sigma, or coherence and averages to compute it")
        g = np.ascontiguousarray(np.atleast_2d(coherence), dtype=np.float64)
        s = _splinewatch.h1_sigma(h, g, int(averages), int(inputs))
    else:
        s = np.ascontiguousarray(np.atleast_2d(sigma), dtype=np.float64)
    return FittedModes(_splinewatch.fit_modes(freqs, h, s, int(modes)))
