#!/usr/bin/env bash
# Builds the guide and takes a screenshot of one page with headless Chromium
# (Debian: apt-get install chromium). Usage:
#   docs/guide/screenshot_guide.sh [PAGE.html] [OUT.png]
set -euo pipefail
page=${1:-concepts/model.html}
out=${2:-/tmp/guide-page.png}
html=$(mktemp -d)
mdbook build "$(dirname "$0")" --dest-dir "$html"
chromium --headless --no-sandbox --disable-gpu --hide-scrollbars --window-size=1280,1400 \
    --screenshot="$out" "file://$html/$page" 2>/dev/null
echo "wrote $out"
