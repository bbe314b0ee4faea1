"""The status page's JSON under load: a daemon with [web] (the demo's, fed
the bundled span at --speed), `replay`s of the bundled recording one after
another beside it on the same machine, and 50 requests a second to /status.json
for DURATION seconds from 4 client threads, each request timed. Prints the
median, 95th percentile and largest latency and the requests that failed.

Usage: python3 benches/status_page_load.py [splinewatch binary] [DURATION]
(run from the repository's root; the binary defaults to the debug build)
"""

import json
import os
import socket
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request

binary = sys.argv[1] if len(sys.argv) > 1 else os.path.expanduser("~/.cache/splinewatch-target/debug/splinewatch")
duration = float(sys.argv[2]) if len(sys.argv) > 2 else 20.0
rate = 50.0

work = tempfile.mkdtemp()
with socket.socket() as s:
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
config = os.path.join(work, "sinello-web.toml")
with open("config/sinello.toml") as f, open(config, "w") as out:
    out.write(f.read() + f'\n[web]\nlisten = "127.0.0.1:{port}"\n')
url = f"http://127.0.0.1:{port}/status.json"
demo = subprocess.Popen(
    [binary, "demo", "--config", config, "--duration", "3600", "--speed", "10", "--out", os.path.join(work, "demo")],
    stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
deadline = time.monotonic() + 60
while time.monotonic() < deadline:
    try:
        with urllib.request.urlopen(url, timeout=2) as r:
            if json.load(r).get("last_update"):
                break
    except OSError:
        pass
    time.sleep(0.5)
else:
    demo.kill()
    sys.exit("the daemon wrote no update within 60 s")
stop = threading.Event()
replays = []


def replay_again():
    """Replays the bundled recording again and again until the load ends."""
    while not stop.is_set():
        p = subprocess.Popen(
            [binary, "replay", "--config", "config/sinello.toml", "--out", os.path.join(work, "replay.mcap"),
             "recordings/sinello-demo.mcap"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        replays.append(p)
        p.wait()


replayer = threading.Thread(target=replay_again)
replayer.start()

latencies, failures, lock = [], [], threading.Lock()
start = time.monotonic()
total = int(duration * rate)


def client(k, threads=4):
    for n in range(k, total, threads):
        due = start + n / rate
        wait = due - time.monotonic()
        if wait > 0:
            time.sleep(wait)
        t0 = time.monotonic()
        try:
            with urllib.request.urlopen(url, timeout=5) as r:
                body = r.read()
                json.loads(body)
            with lock:
                latencies.append(time.monotonic() - t0)
        except (OSError, ValueError) as e:
            with lock:
                failures.append(str(e))


threads = [threading.Thread(target=client, args=(k,)) for k in range(4)]
for t in threads:
    t.start()
for t in threads:
    t.join()
stop.set()
for p in replays:
    p.kill()
replayer.join()
demo.kill()
latencies.sort()
ms = [1e3 * x for x in latencies]
print(f"{len(ms)} requests at {rate:.0f}/s over {duration:.0f} s beside {len(replays)} replays in a row: median {ms[len(ms) // 2]:.1f} ms, "
      f"95th {ms[int(len(ms) * 0.95)]:.1f} ms, largest {ms[-1]:.1f} ms; {len(failures)} failed")
