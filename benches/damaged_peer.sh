#!/usr/bin/env bash
# Issue 34 live: `splinewatch run` on the bundled config fed N (default
# 100 000) damaged messages by a Python zenoh peer (benches/damaged_peer.py;
# pip install eclipse-zenoh cbor2 mcap) over loopback; after SIGTERM the
# daemon's last health message must account for every message received:
# blocks + rejected + queue_drops = received = published. Prints the counts,
# the rejection reasons and the daemon's peak RSS. Needs a release build.
# Usage: benches/damaged_peer.sh [N]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${SPLINEWATCH_BIN:-${CARGO_TARGET_DIR:-target}/release/splinewatch}
count=${1:-100000}
work=$(mktemp -d)
daemon=""
cleanup() {
  [ -n "$daemon" ] && kill "$daemon" 2> /dev/null || true
  wait 2> /dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
port=$((20000 + RANDOM % 20000))
{
  cat config/sinello.toml
  printf '\n[output]\ndir = "%s/out"\n\n[zenoh]\nlisten = ["tcp/127.0.0.1:%d"]\n' "$work" "$port"
} > "$work/live.toml"
"$bin" run --config "$work/live.toml" 2> "$work/daemon.log" &
daemon=$!
sleep 3
start=$(date +%s.%N)
python3 benches/damaged_peer.py "tcp/127.0.0.1:$port" bridge/sinello-span2 "$count"
end=$(date +%s.%N)
sleep 3
peak=$(awk '/VmHWM/ { print $2 }' "/proc/$daemon/status")
kill -TERM "$daemon"
wait "$daemon" || true
daemon=""
echo "published in $(echo "$end - $start" | bc) s; daemon peak RSS ${peak} kB"
grep -E "received|messages" "$work/daemon.log" | tail -2 || true
python3 - "$work/out" "$count" << 'PY'
import glob, json, sys
from mcap.reader import make_reader
last = None
for path in sorted(glob.glob(sys.argv[1] + "/*.mcap")):
    with open(path, "rb") as f:
        for _, c, m in make_reader(f).iter_messages():
            if c.topic.endswith("/health"):
                last = json.loads(m.data)
rejected = sum(last["rejected"].values())
total = last["blocks"] + last.get("temperature_blocks", 0) + rejected + last["queue_drops"]
print(f"blocks {last['blocks']} + rejected {rejected} + queue_drops {last['queue_drops']} = {total} of {sys.argv[2]} published")
print("by reason:", dict(sorted(last["rejected"].items(), key=lambda kv: -kv[1])))
sys.exit(0 if total == int(sys.argv[2]) else 1)
PY
