#!/usr/bin/env bash
# Benchmark (3) of issue 17: the live daemon receiving 64 channels at 2 kHz
# (benches/sinello-64ch.toml: the force at P1 and 63 accelerations, 1-second
# CBOR blocks, 64 messages a second) from `simulate --publish` in real time
# over zenoh on loopback, for SECONDS (default 300). The daemon's CPU time
# and RSS are read from /proc/<pid>/{stat,status} every 10 s; the CPU share
# is taken after the first 30 s (start-up: model assembly, zenoh session).
# 10-minute windows: no window closes and no update runs in 5 minutes, so
# this is the cost of receiving, decoding, aligning and Welch.
# Needs a release build (`cargo build --release`). Usage:
# benches/live_daemon.sh [SECONDS]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${SPLINEWATCH_BIN:-${CARGO_TARGET_DIR:-target}/release/splinewatch}
seconds=${1:-300}
work=$(mktemp -d)
daemon=""
publisher=""
cleanup() {
  [ -n "$publisher" ] && kill "$publisher" 2> /dev/null || true
  [ -n "$daemon" ] && kill "$daemon" 2> /dev/null || true
  wait 2> /dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT
port=$((20000 + RANDOM % 20000))
{
  cat benches/sinello-64ch.toml
  printf '\n[output]\ndir = "%s/out"\n\n[zenoh]\nlisten = ["tcp/127.0.0.1:%d"]\n' "$work" "$port"
} > "$work/live.toml"
"$bin" run --config "$work/live.toml" 2> "$work/daemon.log" &
daemon=$!
sleep 3
"$bin" simulate --config "$work/live.toml" --duration "$((seconds + 10))" --fs 2000 --seed 7 --publish --speed 1 \
  2> "$work/publisher.log" &
publisher=$!
ticks=$(getconf CLK_TCK)
cpu() { awk '{ print $14 + $15 }' "/proc/$daemon/stat"; }
rss() { awk '/VmRSS/ { print $2 }' "/proc/$daemon/status"; }
start_ticks=""
start_time=""
for t in $(seq 10 10 "$seconds"); do
  sleep 10
  now=$(date +%s.%N)
  c=$(cpu)
  if [ "$t" -eq 30 ]; then start_ticks=$c; start_time=$now; fi
  printf 't = %3d s: daemon CPU %6.2f s, RSS %d KiB\n' "$t" "$(echo "$c / $ticks" | bc -l)" "$(rss)"
done
end_ticks=$(cpu)
end_time=$(date +%s.%N)
printf 'daemon CPU from 30 s to %d s: %.2f %% of one core\n' "$seconds" \
  "$(echo "100 * ($end_ticks - $start_ticks) / $ticks / ($end_time - $start_time)" | bc -l)"
kill -TERM "$daemon"
wait "$daemon" || true
daemon=""
grep -E "messages|blocks" "$work/daemon.log" | tail -2
