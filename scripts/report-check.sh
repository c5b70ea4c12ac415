#!/usr/bin/env bash
# Issue 15's browser check: the report of datasets/paper-rig rendered in
# headless Chromium (Debian's chromium, installed by scripts/test.sh). The
# page checks its own plots (every canvas drew) and catches its own errors,
# writing the outcome into #pneumaid-status, which is read from --dump-dom;
# a PNG screenshot is saved beside the report for people to look at.
#   scripts/report-check.sh [BUILD_DIR]     (writes BUILD_DIR/report-check/)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
out="$build/report-check"
mkdir -p "$out"
"$build/pneumaid" identify datasets/paper-rig --out "$out/paper-rig.yaml" >/dev/null
"$build/pneumaid" report --params "$out/paper-rig.yaml" datasets/paper-rig \
  --out "$out/paper-rig.html" >/dev/null
page="file://$(pwd)/$out/paper-rig.html"
flags=(--headless --no-sandbox --disable-gpu --hide-scrollbars --virtual-time-budget=10000)
status=$(timeout 120 chromium "${flags[@]}" --dump-dom "$page" 2>/dev/null |
         grep -o '<div id="pneumaid-status"[^<]*</div>' || true)
timeout 120 chromium "${flags[@]}" --window-size=1280,3000 --screenshot="$out/paper-rig.png" \
  "$page" >/dev/null 2>&1 || true
echo "report check: ${status:-no status element} (screenshot $out/paper-rig.png)"
case "$status" in *'class="ok"'*) ;; *) exit 1 ;; esac
