#!/usr/bin/env bash
# The guide's gallery (docs/guide/src/tutorials/gallery.md): every Python
# example run on the bundled data, its printed output and its figure kept
# in docs/guide/src/images/gallery/. python/tests/test_examples.py checks
# that the examples still print what is kept here.
# Usage, from the repository's root, with the package installed
# (pip install ./python matplotlib) and the CLI built (cargo build):
#   docs/guide/make_gallery.sh [python] [splinewatch]
set -euo pipefail
py="${1:-.venv/bin/python}"
sw="${2:-target/debug/splinewatch}"
out=docs/guide/src/images/gallery
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$out"
"$py" python/examples/model_modes_and_frfs.py > "$out/model_modes_and_frfs.txt"
"$py" python/examples/update_from_synthetic_frfs.py > "$out/update_from_synthetic_frfs.txt"
"$py" python/examples/oma_of_a_recording.py recordings/sinello-demo.mcap --plot "$out/stabilisation.png" \
    | grep -v '^wrote ' > "$out/oma_of_a_recording.txt"
"$sw" replay --config config/sinello.toml recordings/sinello-demo.mcap --out "$tmp/results.mcap" > /dev/null 2>&1
"$py" python/examples/plot_results_trends.py "$tmp/results.mcap" --save "$out/trends.png" \
    | grep -v '^wrote ' > "$out/plot_results_trends.txt"
