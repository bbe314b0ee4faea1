#!/usr/bin/env bash
# Scaling of the sparse path (sparse assembly, nested dissection, supernodal
# Cholesky, Sturm count, shift-invert Lanczos) on the bundled deck refined
# to 325 / 3 200 / 20 000 / 80 000 dofs, modes below 160 Hz (2× the 80 Hz
# band), side by side with scipy's eigsh (ARPACK shift-invert with SuperLU)
# on the matrices `splinewatch matrices` exports, in one run. Peak RSS from
# /usr/bin/time. Needs: a release build, python3 with numpy and scipy.
# Usage: benches/sparse_scaling.sh [PYTHON] [NETS...]
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${CARGO_TARGET_DIR:-target}/release/splinewatch
python=${1:-python3}
shift || true
nets=("${@:-13,5 40,16 100,40 200,80}")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
printf '| net | dofs | modes < 160 Hz | sparse assembly | eigen-solve | peak RSS | scipy eigsh (splu + ARPACK) | scipy peak RSS |\n'
printf '| --- | --- | --- | --- | --- | --- | --- | --- |\n'
for net in ${nets[*]}; do
  m=${net%,*}; n=${net#*,}
  config="$work/net-$m-$n.toml"
  sed "s/control_points = \[13, 5\]/control_points = [$m, $n]/" config/sinello.toml > "$config"
  /usr/bin/time -f '%M' -o "$work/rss" "$bin" modes --config "$config" --cutoff 160 --count 100000 > "$work/modes" 2> "$work/err"
  line=$(grep 'dofs' "$work/err")
  dofs=$(sed -E 's/.*: ([0-9]+) dofs.*/\1/' <<< "$line")
  assembly=$(sed -E 's/.*assembly ([0-9.]+) s.*/\1/' <<< "$line")
  solve=$(sed -E 's/.*eigen-solve ([0-9.]+) s.*/\1/' <<< "$line")
  count=$(($(wc -l < "$work/modes") - 1))
  rss=$(( $(cat "$work/rss") / 1024 ))
  "$bin" matrices --config "$config" --out "$work/mtx-$m-$n" 2> /dev/null
  /usr/bin/time -f '%M' -o "$work/rss-py" "$python" - "$work/mtx-$m-$n" "$count" > "$work/py" <<'PY'
import sys, time
import numpy as np, scipy.io, scipy.sparse.linalg as sla
d = sys.argv[1]
K = scipy.io.mmread(f"{d}/K.mtx").tocsc(); M = scipy.io.mmread(f"{d}/M.mtx").tocsc()
cut = (2 * np.pi * 160.0) ** 2
k = int(sys.argv[2]) + 4  # the count below the cut-off and the same margin as ours
t = time.perf_counter()
w = sla.eigsh(K, k=k, M=M, sigma=-cut / 2500, which="LM", return_eigenvectors=True)[0]
elapsed = time.perf_counter() - t
print(f"{elapsed:.2f} {int((w <= cut).sum())} {k}")
PY
  read -r py_seconds py_count py_k < "$work/py"
  py_rss=$(( $(cat "$work/rss-py") / 1024 ))
  printf '| %s × %s | %s | %s | %s s | %s s | %s MB | %s s (%s modes, k = %s) | %s MB |\n' \
    "$m" "$n" "$dofs" "$count" "$assembly" "$solve" "$rss" "$py_seconds" "$py_count" "$py_k" "$py_rss"
done
