#!/usr/bin/env bash
# Manual interop check over mutual TLS (guide, "Transport security": docs/guide/src/deployment/tls.md):
# a router from config/zenoh/router-tls.json5 (run by eclipse-zenoh in
# Python: no zenohd needed), the splinewatch daemon and a simulated logger
# as its clients, and a Python dashboard that must receive the results and
# a reply to updating/latest. Certificates are made with openssl as the
# guide says.
#
#   tests/interop/run_tls_interop.sh [PYTHON] [SPLINEWATCH]
#
# PYTHON needs `pip install eclipse-zenoh` (1.10); SPLINEWATCH defaults to
# target/debug/splinewatch (cargo build first).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
python=${1:-python3}
splinewatch=${2:-${CARGO_TARGET_DIR:-$root/target}/debug/splinewatch}
work=$(mktemp -d)
trap 'status=$?; kill $(jobs -p) 2>/dev/null || true; if [ $status -ne 0 ]; then tail -n 5 "$work"/*.log; fi; rm -rf "$work"' EXIT
cd "$work"
port=$(( 20000 + RANDOM % 20000 ))
endpoint="tls/127.0.0.1:$port"

# 1. The site PKI, exactly as the guide's step 1 (router for 127.0.0.1).
key() { openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out "$1.key" 2>/dev/null; }
key ca
openssl req -x509 -new -key ca.key -days 3650 -subj "/CN=interop site CA" -out ca.pem \
  -addext basicConstraints=critical,CA:TRUE -addext keyUsage=critical,keyCertSign,cRLSign
key router
openssl req -new -key router.key -subj "/CN=router" -out router.csr
openssl x509 -req -in router.csr -CA ca.pem -CAkey ca.key -CAcreateserial -days 825 -out router.pem \
  -extfile <(printf "subjectAltName=IP:127.0.0.1,DNS:localhost\nextendedKeyUsage=serverAuth") 2>/dev/null
for who in splinewatch logger dashboard; do
  key "$who"
  openssl req -new -key "$who.key" -subj "/CN=$who" -out "$who.csr"
  openssl x509 -req -in "$who.csr" -CA ca.pem -CAkey ca.key -CAcreateserial -days 397 -out "$who.pem" \
    -extfile <(printf "extendedKeyUsage=clientAuth") 2>/dev/null
done

# 2. The router: router-tls.json5 as it is, with this endpoint and these files.
cat > router.py <<PY
import json, time, zenoh
c = zenoh.Config.from_file("$root/config/zenoh/router-tls.json5")
c.insert_json5("listen/endpoints", json.dumps(["$endpoint"]))
for k, f in [("root_ca_certificate", "ca.pem"), ("listen_certificate", "router.pem"), ("listen_private_key", "router.key")]:
    c.insert_json5("transport/link/tls/" + k, json.dumps("$work/" + f))
with zenoh.open(c):
    time.sleep(600)
PY
"$python" router.py &
sleep 2

# 3. The daemon and the logger with their example client files.
for who in splinewatch logger; do
  sed "s#/etc/$who/tls/#$work/#" "$root/config/zenoh/$who-client-tls.json5" > "$who.json5"
done
cat "$root/config/sinello.toml" > site.toml
printf '\n[zenoh]\nmode = "client"\nconnect = ["%s"]\nconfig_file = "%s"\n' "$endpoint" "$work/splinewatch.json5" >> site.toml
"$splinewatch" check-config site.toml
"$splinewatch" run --config site.toml --state state.json --out results.mcap 2> daemon.log &
sleep 2
"$python" "$root/tests/interop/python_tls_dashboard.py" "$endpoint" "$work" 90 &
dashboard=$!
sleep 2
sed "s#config_file = \"$work/splinewatch.json5\"#config_file = \"$work/logger.json5\"#" site.toml > logger.toml
"$splinewatch" simulate --config logger.toml --duration 60 --publish --speed 10 2> logger.log
wait "$dashboard"
echo "interop over mutual TLS: OK"
