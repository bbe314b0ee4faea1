"""oma, identify and frf: the CLI's results bit for bit, documented shapes
and dtypes, bad input raised with its message, no needless copy."""

import json

import numpy as np
import pytest

import splinewatch

SENSORS = [f"P{i}" for i in range(1, 13)]


def _outputs(recording):
    channels = splinewatch.read_recording(recording)
    data = np.column_stack([channels[n].data for n in SENSORS])
    return data, channels["P1"]


def _without_model(cli_json):
    """The CLI's modes JSON without what it adds from the config's model (each
    mode's nearest model mode, `model`): the identification alone, its numbers
    parsed from the same shortest round-trip text, so equal bit for bit."""
    modes = json.loads(cli_json)
    for mode in modes["modes"]:
        assert mode.pop("model")["mac"] > 0
    return modes


def test_oma_is_the_clis_oma_bit_for_bit(cli, ambient):
    # config/sinello-ambient.toml's [oma]: band [0.5, 80], 40 block rows, orders 2-120.
    expected = cli("oma", "--config", "config/sinello-ambient.toml", ambient, "--json").stdout.strip()
    data, first = _outputs(ambient)
    modes = splinewatch.oma(data, first.fs, band=(0.5, 80.0), block_rows=40, orders=(2, 120, 2), sensors=SENSORS,
                            start=first.start)
    assert json.loads(modes.to_json()) == _without_model(expected)
    n = len(modes)
    assert n == len(json.loads(expected)["modes"]) > 10
    for name in ["frequency", "damping", "frequency_std", "damping_std", "mpc"]:
        a = getattr(modes, name)
        assert a.dtype == np.float64 and a.shape == (n,), name
    assert modes.shapes.dtype == np.complex128 and modes.shapes.shape == (n, 12)
    assert modes.shapes_std.shape == (n, 12) and modes.order.dtype == np.int64
    assert np.all(np.diff(modes.frequency) > 0)
    diagram = modes.stabilisation
    assert diagram["stable"].dtype == bool and len(diagram["order"]) == len(diagram["frequency"])
    assert set(diagram["mode"][diagram["mode"] >= 0]) == set(range(n))


def _two_modes(u, fs):
    """Two SDOF modes (1.5 Hz, 4 Hz, 2 % damping) driven by `u`, seen at three channels (ZOH: exact poles)."""
    from scipy.signal import cont2discrete, lfilter

    def mode(f, zeta):
        w = 2 * np.pi * f
        b, a, _ = cont2discrete(([w * w], [1.0, 2 * zeta * w, w * w]), 1 / fs, method="zoh")
        return lfilter(b[0], a, u)

    q = np.column_stack([mode(1.5, 0.02), mode(4.0, 0.02)])
    return q @ np.array([[1.0, 0.6, -0.4], [0.5, -1.0, 0.9]])


def test_fortran_ordered_data_is_read_in_place_and_gives_the_same_modes():
    rng = np.random.default_rng(7)
    fs = 50.0
    data = _two_modes(rng.standard_normal(30_000), fs)
    c = splinewatch.oma(data, fs, orders=(2, 30), block_rows=20)
    f = splinewatch.oma(np.asfortranarray(data), fs, orders=(2, 30), block_rows=20)
    assert c.copied and not f.copied
    assert len(c) >= 2 and c.to_json() == f.to_json()


def test_frf_is_the_clis_frf_bit_for_bit(cli, forced):
    expected = json.loads(cli("frf", "--config", "config/sinello.toml", forced).stdout)
    force = splinewatch.read_recording(forced, quantity="force")["P1"]
    accelerations = splinewatch.read_recording(forced)
    responses = np.column_stack([accelerations[n].data for n in SENSORS])
    # config/sinello.toml's [frf]: 4 s Hann segments, half overlap, H1, band [0.5, 80].
    f, h, coherence = splinewatch.frf(force.data, responses, force.fs, segment_seconds=4.0, band=(0.5, 80.0))
    assert f.dtype == np.float64 and h.dtype == np.complex128 and coherence.dtype == np.float64
    assert h.shape == coherence.shape == (12, len(f))
    assert f.tolist() == expected["frequency_hz"]
    for row, entry in enumerate(expected["frfs"]):
        assert h[row].real.tolist() == entry["re"] and h[row].imag.tolist() == entry["im"]
        assert np.clip(coherence[row], 0.0, 1.0).tolist() == entry["coherence"]


def test_identify_is_the_clis_identify_bit_for_bit(cli, forced):
    # The bundled deck's shaker record: the force at P1 in, every accelerometer out;
    # config/sinello.toml has no [oma]: horizon 40, orders 2-120, 16 batches, band [frf] [0.5, 80],
    # exact jackknife (identify's).
    expected = cli("identify", "--config", "config/sinello.toml", forced, "--json").stdout.strip()
    force = splinewatch.read_recording(forced, quantity="force")["P1"]
    responses = splinewatch.read_recording(forced)
    outputs = np.column_stack([responses[n].data for n in SENSORS])
    modes = splinewatch.identify(force.data, outputs, force.fs, band=(0.5, 80.0), horizon=40, orders=(2, 120, 2),
                                 batches=16, sensors=SENSORS, start=force.start)
    assert json.loads(modes.to_json()) == _without_model(expected)
    assert len(modes) >= 8


def test_identify_recovers_a_two_mode_system_driven_by_a_measured_input():
    rng = np.random.default_rng(11)
    fs = 50.0
    u = rng.standard_normal(6000)
    y = _two_modes(u, fs)
    y += 0.02 * y.std(axis=0) * rng.standard_normal(y.shape)
    modes = splinewatch.identify(u, y, fs, horizon=20, orders=(2, 20), batches=6)
    found = sorted(modes.frequency)
    assert len(found) >= 2
    for target in (1.5, 4.0):
        nearest = min(found, key=lambda f: abs(f - target))
        # exact discrete poles (ZOH), 2 % output noise, 120 s: within 1 %
        assert abs(nearest - target) / target < 0.01
    assert np.all(np.isfinite(modes.frequency_std))


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda d: splinewatch.oma(d[:, :0], 50.0), "samples × channels"),
        (lambda d: splinewatch.oma(d[:1], 50.0), "at least 2 samples"),
        (lambda d: splinewatch.oma(d, 0.0), "fs must be a positive sampling frequency"),
        (lambda d: splinewatch.oma(d, float("nan")), "fs must be a positive sampling frequency"),
        (lambda d: splinewatch.oma(np.where(np.arange(len(d))[:, None] == 17, np.nan, d), 50.0), "data[17, 0] is NaN"),
        (lambda d: splinewatch.oma(d, 50.0, uncertainty="bootstrap"), "unknown variant `bootstrap`"),
        (lambda d: splinewatch.oma(d, 50.0, orders=(10, 2)), "min_order must not exceed max_order"),
        (lambda d: splinewatch.oma(d, 50.0, references=[5]), "references: channel 5 does not exist"),
        (lambda d: splinewatch.oma(d, 50.0, stability={"bogus": 1}), "unknown field `bogus`"),
        (lambda d: splinewatch.oma(np.zeros((2, 3, 4)), 50.0), "2-D"),
        (lambda d: splinewatch.identify(d[:100, :1], d[:90], 50.0), "inputs have 100 samples, outputs 90"),
        (lambda d: splinewatch.frf(d[:, 0], d, 50.0, window="kaiser"), "\"kaiser\" is not rectangular"),
        (lambda d: splinewatch.frf(d[:, 0], d, 50.0, segment_seconds=1000.0), "responses must be samples × channels"),
    ],
)
def test_bad_input_raises_a_value_error_naming_what_was_wrong(call, message):
    d = np.random.default_rng(1).standard_normal((4000, 3))
    with pytest.raises(ValueError) as raised:
        call(d)
    assert message in str(raised.value)
