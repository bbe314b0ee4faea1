#!/usr/bin/env bash
# Issue 48: 10 000 asks for `updating/latest` over mutual TLS (the router of
# config/zenoh/router-tls.json5 with its access control, the daemon a
# client, a dashboard client asking), each answered on its first ask, while
# the daemon is still analysing and publishing the logger's recording. Before
# vendor/zenoh-link-tls, 3 of 9 runs of 50 asks lost one under CPU load.
# Usage: benches/tls_asks.sh [ASKS] [RUNS]
set -euo pipefail
cd "$(dirname "$0")/.."
asks="${1:-10000}"
runs="${2:-1}"
for run in $(seq 1 "$runs"); do
  SPLINEWATCH_TLS_ASKS="$asks" cargo test --quiet --test integration \
    security::mutual_tls_admits_the_site_ca_clients_only_and_keeps_the_access_control \
    -- --nocapture 2>&1 | grep -E "asks, each|panicked|ask [0-9]+ of|test result" || true
done
