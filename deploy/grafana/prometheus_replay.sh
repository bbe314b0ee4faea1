#!/usr/bin/env bash
# A real Prometheus (Debian's `prometheus` package: apt install prometheus)
# scraping `splinewatch replay --metrics` of the bundled recording every
# second, then asked through its HTTP API what it stored: the check that the
# exposition is one Prometheus itself takes, and the queries the Grafana
# dashboard (splinewatch.json) runs. Usage, from the repository root:
#   deploy/grafana/prometheus_replay.sh [splinewatch binary]
set -euo pipefail
bin="${1:-target/release/splinewatch}"
work="$(mktemp -d)"
trap 'kill "${prom:-0}" 2>/dev/null || true; rm -rf "$work"' EXIT
port=19464
prom_port=19090
cp config/sinello.toml "$work/config.toml"
printf '\n[metrics]\nlisten = "127.0.0.1:%s"\n' "$port" >> "$work/config.toml"
cat > "$work/prometheus.yml" <<YML
global: {scrape_interval: 1s}
scrape_configs:
  - job_name: splinewatch
    static_configs: [{targets: ["127.0.0.1:$port"]}]
YML
prometheus --config.file="$work/prometheus.yml" --storage.tsdb.path="$work/tsdb" \
  --web.listen-address="127.0.0.1:$prom_port" --log.level=warn > "$work/prometheus.log" 2>&1 &
prom=$!
sleep 2
"$bin" replay --config "$work/config.toml" recordings/sinello-demo.mcap --out "$work/replay.mcap" \
  --single-thread --metrics --metrics-linger 6 > /dev/null 2>&1
query() {
  curl -s --get "http://127.0.0.1:$prom_port/api/v1/query" --data-urlencode "query=$1" | python3 -c '
import json, sys
result = json.load(sys.stdin)["data"]["result"]
for r in result:
    m = r["metric"]
    print("  " + m.get("parameter", m.get("__name__", "")) + " = " + r["value"][1])
if not result:
    print("  (none)")
'
}
for q in 'up{job="splinewatch"}' \
         'max_over_time(splinewatch_update_runs_total[1m])' \
         'max_over_time(splinewatch_blocks_accepted_total[1m])' \
         'histogram_quantile(0.95, sum by (le) (max_over_time(splinewatch_update_duration_seconds_bucket[1m])))' \
         'last_over_time(splinewatch_parameter_value{parameter=~"east.k.*"}[1m])'; do
  echo "$q"
  query "$q"
done
