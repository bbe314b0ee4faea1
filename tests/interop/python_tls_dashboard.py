"""A Python dashboard (eclipse-zenoh) over mutual TLS: a manual interop check.

    python tests/interop/python_tls_dashboard.py ENDPOINT PKI_DIR [SECONDS]

Connects to ENDPOINT (tls/host:port) as the `dashboard` client of
config/zenoh/dashboard-client-tls.json5 with PKI_DIR/{ca,dashboard}.pem and
dashboard.key, subscribes to bridge/*/updating/parameters for SECONDS
(default 60), then queries bridge/*/updating/latest and prints what it got.
Exits non-zero unless it received at least one parameters message and one
reply. tests/interop/run_tls_interop.sh runs it against a router, the daemon
and a logger, all over mutual TLS (guide, "Transport security": docs/guide/src/deployment/tls.md).
"""

import json
import sys
import time
from pathlib import Path

import zenoh

ROOT = Path(__file__).resolve().parents[2]


def main():
    endpoint, pki = sys.argv[1], Path(sys.argv[2])
    seconds = float(sys.argv[3]) if len(sys.argv) > 3 else 60.0
    conf = zenoh.Config.from_file(str(ROOT / "config/zenoh/dashboard-client-tls.json5"))
    conf.insert_json5("connect/endpoints", json.dumps([endpoint]))
    for key, name in [("root_ca_certificate", "ca.pem"), ("connect_certificate", "dashboard.pem"),
                      ("connect_private_key", "dashboard.key")]:
        conf.insert_json5(f"transport/link/tls/{key}", json.dumps(str(pki / name)))
    received = []
    with zenoh.open(conf) as session:
        sub = session.declare_subscriber("bridge/*/updating/parameters",
                                         lambda s: received.append(json.loads(s.payload.to_bytes())))
        deadline = time.time() + seconds
        while time.time() < deadline and len(received) < 2:
            time.sleep(0.5)
        replies = []
        for reply in session.get("bridge/*/updating/latest", timeout=5.0):
            if reply.ok is not None:
                replies.append((str(reply.ok.key_expr), json.loads(reply.ok.payload.to_bytes())))
        sub.undeclare()
    print(f"python dashboard over mutual TLS: {len(received)} parameters messages received")
    for key, body in replies:
        names = [p["name"] for p in body.get("parameters", [])]
        print(f"  reply on {key}: window {body.get('window')}, {len(names)} parameters ({', '.join(names[:3])}, …)")
    if not received or not replies:
        sys.exit("no parameters or no reply to updating/latest")


if __name__ == "__main__":
    main()
