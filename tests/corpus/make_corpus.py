"""Writes the nasty-input corpus of tests/corpus.rs: one file per message in
wire/, and corpus.json saying, for each, its MCAP channel (topic suffix and
message encoding), the health counter that must reject it, and where it is
spliced into the bundled recording (after which of its messages; -1 = before
the first one).

Run from this folder (needs cbor2 and mcap): python3 make_corpus.py
Deterministic: the same files every time.
"""
import json
import math
import struct

import cbor2
from mcap.reader import make_reader

RECORDING = "../../recordings/sinello-demo.mcap"
PREFIX = "bridge/sinello-span2/"

with open(RECORDING, "rb") as fh:
    messages = [(ch.topic, ch.message_encoding, m.data) for _, ch, m in make_reader(fh).iter_messages()]


def block(index):
    """Block `index` of the recording, decoded (the typed array kept as a tag)."""
    return cbor2.loads(messages[index][2])


def find(name, k):
    """Index of the k-th message of channel `name`."""
    hits = [i for i, (t, _, _) in enumerate(messages) if t.endswith("/" + name)]
    return hits[k]


def stamp_shift(ts, ns):
    """RFC 3339 timestamp `ts` (…Z, 9 decimals) moved by `ns`."""
    import datetime

    base, _, frac = ts[:-1].partition(".")
    t = datetime.datetime.strptime(base, "%Y-%m-%dT%H:%M:%S").replace(tzinfo=datetime.timezone.utc)
    total = int(t.timestamp()) * 10**9 + int(frac.ljust(9, "0")) + ns
    s, f = divmod(total, 10**9)
    return datetime.datetime.fromtimestamp(s, tz=datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%S") + f".{f:09d}Z"


def with_(b, **kw):
    b = dict(b)
    b.update(kw)
    return b


valid = block(find("P3", 10))
FS = valid["fs"]
entries = []


def add(name, payload, reason, after, topic="accel/P3", encoding="cbor"):
    ext = {"cbor": "cbor", "json": "json"}.get(encoding, "bin")
    file = f"{len(entries):02d}-{name}.{ext}"
    with open("wire/" + file, "wb") as fh:
        fh.write(payload)
    entries.append({"file": file, "topic": topic, "encoding": encoding, "reason": reason, "after": after})


# Before any valid data: a bad first block must not poison the stream.
first = block(find("P1", 0))
add("first-block-in-2099", cbor2.dumps(with_(first, start_timestamp="2099-01-01T00:00:00.000000000Z")), "far_future", -1, "force/P1")
p2 = block(find("P2", 0))
add("first-block-wrong-rate", cbor2.dumps(with_(p2, fs=1000.0)), "rate_mismatch", -1, "accel/P2")

# Decoder rejections, spread over the stream.
whole = cbor2.dumps(valid)
add("truncated-cbor", whole[: len(whole) // 2], "malformed", 100)
add("empty-payload", b"", "malformed", 110)
add("cbor-2GB-byte-string-claim", cbor2.dumps(with_(valid, data=None))[:-1] + b"\xd8\x56\x5a\x80\x00\x00\x00" + b"\x00" * 16, "malformed", 120)
add("cbor-1e9-item-array-claim", cbor2.dumps(with_(valid, data=None))[:-1] + b"\x9a\x3b\x9a\xca\x00" + b"\xfb" + struct.pack(">d", 1.0), "malformed", 130)
nan = struct.pack("<4d", 0.0, 1.0, math.nan, 2.0)
add("nan-in-typed-array", cbor2.dumps(with_(valid, data=cbor2.CBORTag(86, nan))), "non_finite", 140)
add("infinity-in-plain-array", cbor2.dumps(with_(valid, data=[0.0, math.inf, 1.0])), "non_finite", 150)
add("typed-array-ragged-bytes", cbor2.dumps(with_(valid, data=cbor2.CBORTag(86, b"\x00" * 13))), "bad_field", 160)
add("typed-array-unknown-tag", cbor2.dumps(with_(valid, data=cbor2.CBORTag(72, b"\x00" * 16))), "bad_field", 170)
add("fs-zero", cbor2.dumps(with_(valid, fs=0.0)), "bad_fs", 180)
add("fs-negative", cbor2.dumps(with_(valid, fs=-FS)), "bad_fs", 190)
add("fs-nan", cbor2.dumps(with_(valid, fs=math.nan)), "bad_fs", 200)
add("fs-a-string", cbor2.dumps(with_(valid, fs="256 Hz")), "bad_field", 210)
add("fs-a-byte-string", cbor2.dumps(with_(valid, fs=b"\x01")), "bad_field", 220)
add("name-missing", cbor2.dumps({k: v for k, v in valid.items() if k != "name"}), "bad_field", 230)
add("name-with-slash", cbor2.dumps(with_(valid, name="P3/../P1")), "bad_name", 240)
add("name-empty", cbor2.dumps(with_(valid, name="")), "bad_name", 250)
add("quantity-strain", cbor2.dumps(with_(valid, quantity="strain")), "bad_quantity", 260)
add("timestamp-garbage", cbor2.dumps(with_(valid, start_timestamp="yesterday noon")), "bad_timestamp", 270)
add("timestamp-an-integer", cbor2.dumps(with_(valid, start_timestamp=1795255200)), "bad_field", 280)
add("data-empty", cbor2.dumps(with_(valid, data=[])), "empty", 290)
add("data-strings", cbor2.dumps(with_(valid, data=["1.0", "2.0"])), "bad_field", 300)
add("block-a-number", cbor2.dumps(42), "bad_field", 310)
add("cbor-nesting-20000", b"\x81" * 20_000 + b"\x00", "malformed", 320)
add("list-of-300-blocks", cbor2.dumps([with_(valid, data=[1.0])] * 300), "too_many_samples", 330)
add("list-with-one-bad-block", cbor2.dumps([valid, with_(valid, fs=-1.0)]), "bad_fs", 340)
add("json-truncated", json.dumps({"name": "P3", "quantity": "acceleration", "fs": FS}).encode()[:-5], "malformed", 350, encoding="json")
add("json-number-out-of-range", b'{"name":"P3","quantity":"acceleration","fs":1e999,"start_timestamp":"2026-11-21T10:00:00Z","data":[1]}', "malformed", 360, encoding="json")
add("json-nesting-20000", b"[" * 20_000 + b"]" * 20_000, "malformed", 370, encoding="json")
add("json-byte-order-mark", b"\xef\xbb\xbf" + json.dumps({"name": "P3"}).encode(), "malformed", 380, encoding="json")
add("json-fs-a-string", json.dumps({"name": "P3", "quantity": "acceleration", "fs": "fast", "start_timestamp": "2026-11-21T10:00:00Z", "data": [1.0]}).encode(), "bad_field", 390, encoding="json")
add("unknown-message-encoding", whole, "unknown_encoding", 400, encoding="protobuf")

# Valid encoding, rejected by the pipeline.
add("unknown-sensor", cbor2.dumps(with_(valid, name="P99")), "unknown_channel", 410, "accel/P99")
add("force-on-an-accelerometer", cbor2.dumps(with_(valid, quantity="force")), "unknown_channel", 420, "force/P3")
add("other-rate-interleaved", cbor2.dumps(with_(block(find("P5", 40)), fs=FS / 2)), "rate_mismatch", 540, "accel/P5")
dup_src = find("P4", 50)
add("duplicate-block", messages[dup_src][2], "time_overlap", dup_src + 100, "accel/P4")
back = block(find("P6", 100))
add("backwards-30s", cbor2.dumps(with_(back, start_timestamp=stamp_shift(back["start_timestamp"], -30 * 10**9))), "time_overlap", find("P6", 100) + 13, "accel/P6")
half = block(find("P7", 60))
add("half-sample-misaligned", cbor2.dumps(with_(half, start_timestamp=stamp_shift(half["start_timestamp"], int(0.5e9 / FS)))), "misaligned", find("P7", 60) + 13, "accel/P7")
add("mid-stream-block-in-2099", cbor2.dumps(with_(block(find("P8", 70)), start_timestamp="2099-06-01T00:00:00.000000000Z")), "far_future", find("P8", 70) - 13, "accel/P8")

with open("corpus.json", "w") as fh:
    json.dump(entries, fh, indent=1)
    fh.write("\n")
print(f"wrote {len(entries)} files")
