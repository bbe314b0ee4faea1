"""read_recording and read_results against the Python `mcap` package (an
independent reader and writer) on the repository's fixtures and the
CLI's own results files."""

import json

import cbor2
import numpy as np
import pytest
from mcap.reader import make_reader
from mcap.writer import Writer

import splinewatch

START_NS = 1_795_255_200_000_000_000  # 2026-11-21T10:00:00Z


def test_a_recording_written_by_another_library_reads_as_it_was_written(repo):
    # tests/fixtures/make_python_mcap.py: force 0..11 on P1, acceleration half of it on P2, 8 Hz, 3 blocks.
    path = repo / "tests/fixtures/python_recording.mcap"
    force = splinewatch.read_recording(path, quantity="force")
    accel = splinewatch.read_recording(path)
    assert list(force) == ["P1"] and list(accel) == ["P2"]
    assert force["P1"].data.tolist() == [float(v) for v in range(12)]
    assert accel["P2"].data.tolist() == [0.5 * v for v in range(12)]
    assert accel["P2"].fs == 8.0 and accel["P2"].start == np.datetime64(START_NS, "ns")
    assert accel["P2"].missing == 0 and accel["P2"].unit == "m/s^2"
    assert accel["P2"].time[1] - accel["P2"].time[0] == np.timedelta64(125_000_000, "ns")
    both = splinewatch.read_recording(path, quantity=None)
    assert set(both) == {("P1", "force"), ("P2", "acceleration")}


def _stamp(ns):
    return np.datetime_as_string(np.datetime64(ns, "ns"), unit="ns") + "Z"


def _write_a1(path, fs, blocks, extra_payload=None):
    """A recording of channel A1's acceleration: (start ns, samples) blocks as CBOR, and
    `extra_payload` (raw bytes) as one more message on the same topic."""
    with open(path, "wb") as fh:
        w = Writer(fh)
        w.start(profile="", library="splinewatch python test")
        channel = w.register_channel(topic="bridge/t/accel/A1", message_encoding="cbor", schema_id=0)
        for t, data in blocks:
            block = {"name": "A1", "quantity": "acceleration", "unit_str": "m/s^2", "fs": fs,
                     "start_timestamp": _stamp(t), "data": data}
            w.add_message(channel_id=channel, log_time=t, data=cbor2.dumps(block), publish_time=t)
        if extra_payload is not None:
            w.add_message(channel_id=channel, log_time=START_NS, data=extra_payload, publish_time=START_NS)
        w.finish()


def test_gaps_are_nan_and_an_undecodable_message_is_reported_not_dropped(tmp_path):
    path = tmp_path / "gappy.mcap"
    # The block of second 1 is missing; a truncated CBOR map follows.
    blocks = [(START_NS + k * 1_000_000_000, [float(k)] * 4) for k in (0, 2)]
    _write_a1(path, 4.0, blocks, extra_payload=b"\xa1\x64name")
    with pytest.warns(UserWarning, match="skipped a message on bridge/t/accel/A1"):
        channels = splinewatch.read_recording(path)
    a1 = channels["A1"]
    assert a1.missing == 4 and len(a1.data) == 12
    assert np.isnan(a1.data[4:8]).all() and a1.data[8:].tolist() == [2.0] * 4


def test_results_are_the_files_messages_as_arrays(cli, forced, tmp_path):
    results_path = tmp_path / "results.mcap"
    cli("replay", "--config", "config/sinello.toml", forced, "--out", results_path)
    results = splinewatch.read_results(results_path)
    with open(results_path, "rb") as fh:
        independent = [
            (channel.topic, json.loads(message.data))
            for _, channel, message in make_reader(fh).iter_messages()
            if channel.message_encoding == "json"
        ]
    updates = [m for t, m in independent if t.endswith("/updating/parameters")]
    assert len(updates) >= 2 and results.prefix == "bridge/sinello-span2"
    assert len(results.updates["window"]) == len(updates)
    assert results.updates["window"].tolist() == [m["window"] for m in updates]
    for name, columns in results.parameters.items():
        expected = [p["value"] for m in updates for p in m["parameters"] if p["name"] == name]
        assert columns["value"].tolist() == expected
        assert columns["time"].dtype == np.dtype("datetime64[ns]") and columns["std"].dtype == np.float64
    assert "west.k1" in results.parameters and "windows" in results.topics
    assert len(results.messages("windows")) == sum(1 for t, _ in independent if t.endswith("/windows"))
    fit = results.frf_fit()
    last = [m for t, m in independent if t.endswith("/frf/model")][-1]
    assert fit["window"] == last["window"] and fit["measured"].shape == fit["model"].shape
    assert fit["model"][0].real.tolist() == last["frfs"][0]["re"] and fit["frequency"].tolist() == last["frequency_hz"]
    with pytest.raises(ValueError, match="has no measured FRFs"):
        results.frf_fit(window=10_000)
    frames = results.to_pandas()
    assert len(frames["parameters"]) == sum(len(c["value"]) for c in results.parameters.values())


def test_missing_and_foreign_files_raise_with_the_clis_message(tmp_path):
    with pytest.raises(FileNotFoundError, match="cannot read"):
        splinewatch.read_results(tmp_path / "none.mcap")
    text = tmp_path / "not.mcap"
    text.write_text("hello")
    with pytest.raises(ValueError, match="not an MCAP file"):
        splinewatch.read_recording(text)
    with pytest.raises(ValueError, match="not an MCAP file"):
        splinewatch.read_results(text)


def test_a_block_decades_off_is_an_error_not_a_terabyte_grid(tmp_path):
    path = tmp_path / "far.mcap"
    far = START_NS + 73 * 365 * 86_400 * 1_000_000_000  # the corpus's block of 2099
    _write_a1(path, 256.0, [(START_NS, [0.0] * 4), (far, [0.0] * 4)])
    with pytest.raises(ValueError, match='channel "A1" spans .* a block with a wrong time'):
        splinewatch.read_recording(path)
