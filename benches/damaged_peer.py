#!/usr/bin/env python3
"""Issue 34 live: a Python zenoh peer publishing damaged messages.

Draws N messages (default 100 000) at random from the bundled recording
(out of order, repeated), damages 70 % of them with the issue's mutation
classes (bit flips, truncation, random bytes, bytes inserted; a field set
to null / NaN / 1e308 / a long string / an empty list, a field removed, a
zero, negative, infinite or string rate, an impossible or far-future
timestamp) and publishes them, CBOR, on the daemon's topics with
congestion control `block` (the transport drops nothing). Seeded.
Usage: damaged_peer.py ENDPOINT PREFIX [N] [SEED]; run by
benches/damaged_peer.sh.
"""
import math
import random
import sys

import cbor2
import zenoh
from mcap.reader import make_reader


def damage(rng, data):
    out = bytearray(data)
    cls = rng.randrange(9)
    if cls == 0:
        for _ in range(rng.randint(1, 8)):
            out[rng.randrange(len(out))] ^= 1 << rng.randrange(8)
    elif cls == 1:
        del out[rng.randrange(len(out)):]
    elif cls == 2:
        out = bytearray(rng.randbytes(rng.randrange(256)))
    elif cls == 3:
        at = rng.randrange(len(out) + 1)
        out[at:at] = rng.randbytes(rng.randint(1, 16))
    else:
        fields = cbor2.loads(data)
        keys = list(fields)
        if cls == 4:
            fields[rng.choice(keys)] = rng.choice([None, math.nan, 1e308, "x" * 100_000, []])
        elif cls == 5:
            del fields[rng.choice(keys)]
        elif cls == 6:
            fields["fs"] = rng.choice([0.0, -256.0, math.inf, "256"])
        else:
            fields["start_timestamp"] = rng.choice(
                ["2026-13-45T99:99:99Z", "0000-01-01T00:00:00Z", "9999-12-31T23:59:59Z", "2100-01-01T00:00:00Z"]
            )
        out = bytearray(cbor2.dumps(fields))
    return bytes(out)


def main():
    endpoint, prefix = sys.argv[1], sys.argv[2]
    count = int(sys.argv[3]) if len(sys.argv) > 3 else 100_000
    rng = random.Random(int(sys.argv[4]) if len(sys.argv) > 4 else 34)
    with open("recordings/sinello-demo.mcap", "rb") as f:
        messages = [(c.topic, m.data) for _, c, m in make_reader(f).iter_messages()]
    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", f'["{endpoint}"]')
    conf.insert_json5("scouting/multicast/enabled", "false")
    session = zenoh.open(conf)
    publishers = {}
    damaged = 0
    for _ in range(count):
        topic, data = rng.choice(messages)
        if rng.random() < 0.7:
            data = damage(rng, data)
            damaged += 1
        if topic not in publishers:
            publishers[topic] = session.declare_publisher(
                topic,
                encoding=zenoh.Encoding.APPLICATION_CBOR,
                congestion_control=zenoh.CongestionControl.BLOCK,
            )
        publishers[topic].put(data)
    session.close()
    print(f"published {count} messages ({damaged} damaged) under {prefix}")


if __name__ == "__main__":
    main()
