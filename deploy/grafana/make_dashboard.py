"""Writes splinewatch.json, the Grafana dashboard over a splinewatch
daemon's `/metrics` ([metrics], issue 48). Run from anywhere:
    python3 deploy/grafana/make_dashboard.py
The test `issue_48_the_grafana_dashboard_queries_only_metrics_the_daemon_serves`
checks that every metric the dashboard queries is one the daemon exports.
"""

import json
from pathlib import Path

DATASOURCE = {"type": "prometheus", "uid": "${datasource}"}
OUTCOME_PROCESSED = 'outcome="processed"'
PARAMETER = 'parameter=~"$parameter"'


def sel(extra=""):
    """The label selector of every query: the chosen bridges (and `extra`)."""
    return '{bridge=~"$bridge"' + ("," + extra if extra else "") + "}"


B = sel()


def timeseries(id_, title, exprs, x, y, w=12, h=8, unit="short"):
    return {
        "id": id_,
        "type": "timeseries",
        "title": title,
        "datasource": DATASOURCE,
        "gridPos": {"x": x, "y": y, "w": w, "h": h},
        "targets": [{"refId": chr(65 + i), "expr": e, "legendFormat": legend} for i, (e, legend) in enumerate(exprs)],
        "fieldConfig": {"defaults": {"unit": unit}, "overrides": []},
        "options": {"legend": {"displayMode": "list", "placement": "bottom"}, "tooltip": {"mode": "multi"}},
    }


def stat(id_, title, expr, x, y, unit="short", mappings=None):
    return {
        "id": id_,
        "type": "stat",
        "title": title,
        "datasource": DATASOURCE,
        "gridPos": {"x": x, "y": y, "w": 4, "h": 4},
        "targets": [{"refId": "A", "expr": expr}],
        "fieldConfig": {"defaults": {"unit": unit, "mappings": mappings or []}, "overrides": []},
        "options": {"reduceOptions": {"calcs": ["lastNotNull"]}, "colorMode": "background"},
    }


def row(id_, title, y):
    return {"id": id_, "type": "row", "title": title, "gridPos": {"x": 0, "y": y, "w": 24, "h": 1}, "collapsed": False, "panels": []}


def quantiles(metric):
    return [
        (f"histogram_quantile({q}, sum by (bridge, le) (rate({metric}_bucket{B}[15m])))", "{{bridge}} p" + str(int(q * 100)))
        for q in (0.5, 0.95)
    ]


ALARM = [{"type": "value", "options": {"0": {"text": "normal", "color": "green"}, "1": {"text": "ALARM", "color": "red"}}}]
panels = [
    row(1, "Health", 0),
    stat(2, "Alarm", f"max by (bridge) (splinewatch_alarm{B})", 0, 1, mappings=ALARM),
    stat(3, "Last update age", f"max by (bridge) (splinewatch_last_update_age_seconds{B})", 4, 1, unit="s"),
    stat(4, "Relative residual", f"max by (bridge) (splinewatch_last_update_relative_residual{B})", 8, 1),
    stat(5, "Update failures (1 h)", f"sum by (bridge) (increase(splinewatch_update_failures_total{B}[1h]))", 12, 1),
    stat(6, "Queue drops (1 h)", f"sum by (bridge) (increase(splinewatch_queue_drops_total{B}[1h]))", 16, 1),
    stat(7, "Events processed", f"sum by (bridge) (splinewatch_events_total{sel(OUTCOME_PROCESSED)})", 20, 1),
    row(8, "Throughput", 5),
    timeseries(9, "Messages and blocks per second", [
        (f"sum by (bridge) (rate(splinewatch_messages_received_total{B}[5m]))", "{{bridge}} received"),
        (f"sum by (bridge) (rate(splinewatch_blocks_accepted_total{B}[5m]))", "{{bridge}} accepted"),
        (f"sum by (bridge, reason) (rate(splinewatch_rejected_total{B}[5m]))", "{{bridge}} rejected: {{reason}}"),
    ], 0, 6, unit="ops"),
    timeseries(10, "Windows and updates per hour", [
        (f"sum by (bridge) (increase(splinewatch_windows_accepted_total{B}[1h]))", "{{bridge}} windows"),
        (f"sum by (bridge, reason) (increase(splinewatch_windows_skipped_total{B}[1h]))", "{{bridge}} windows skipped: {{reason}}"),
        (f"sum by (bridge) (increase(splinewatch_update_runs_total{B}[1h]))", "{{bridge}} updates"),
        (f"sum by (bridge, reason) (increase(splinewatch_updates_skipped_total{B}[1h]))", "{{bridge}} updates skipped: {{reason}}"),
    ], 12, 6),
    timeseries(11, "Queues", [
        (f"max by (bridge) (splinewatch_update_queue_depth{B})", "{{bridge}} update queue"),
        (f"max by (bridge) (splinewatch_ingest_queue_depth{B})", "{{bridge}} ingest queue"),
    ], 0, 14),
    timeseries(12, "Output errors and notifications per hour", [
        (f"sum by (bridge, output) (increase(splinewatch_output_errors_total{B}[1h]))", "{{bridge}} {{output}} errors"),
        (f"sum by (bridge, outcome) (increase(splinewatch_notifications_total{B}[1h]))", "{{bridge}} notifications {{outcome}}"),
    ], 12, 14),
    row(13, "Latency", 22),
    timeseries(14, "Update duration (p50, p95)", quantiles("splinewatch_update_duration_seconds"), 0, 23, unit="s"),
    timeseries(15, "Ingest-to-result latency (p50, p95)", quantiles("splinewatch_result_latency_seconds"), 12, 23, unit="s"),
    row(16, "The structure", 31),
    timeseries(17, "Updated parameters", [(f"splinewatch_parameter_value{sel(PARAMETER)}", "{{bridge}} {{parameter}}")], 0, 32, w=24, h=9),
    timeseries(18, "Monitoring: standardised residuals", [(f"splinewatch_monitoring_residual{B}", "{{bridge}} {{feature}}")], 0, 41),
    timeseries(19, "Monitoring state", [(f"splinewatch_monitoring_state{B} == 1", "{{bridge}} {{state}}")], 12, 41),
]
variables = [
    {"name": "datasource", "type": "datasource", "query": "prometheus", "label": "Prometheus"},
    {"name": "bridge", "type": "query", "datasource": DATASOURCE, "query": "label_values(splinewatch_blocks_accepted_total, bridge)",
     "includeAll": True, "multi": True, "current": {"text": "All", "value": "$__all"}, "refresh": 2},
    {"name": "parameter", "type": "query", "datasource": DATASOURCE,
     "query": 'label_values(splinewatch_parameter_value{bridge=~"$bridge"}, parameter)',
     "includeAll": True, "multi": True, "current": {"text": "All", "value": "$__all"}, "refresh": 2},
]
dashboard = {
    "title": "splinewatch",
    "uid": "splinewatch",
    "schemaVersion": 39,
    "version": 1,
    "editable": True,
    "tags": ["splinewatch", "shm"],
    "time": {"from": "now-24h", "to": "now"},
    "refresh": "30s",
    "description": "splinewatch daemons: health, throughput, latency, the updated parameters and the alarm state "
    "(the guide: docs/guide/src/deployment/metrics.md). Made by deploy/grafana/make_dashboard.py.",
    "templating": {"list": variables},
    "panels": panels,
}
(Path(__file__).parent / "splinewatch.json").write_text(json.dumps(dashboard, indent=1) + "\n")
