#!/usr/bin/env bash
# Issue 15's browser check: three reports rendered in headless Chromium
# (Debian's chromium, installed by scripts/test.sh): the unit report of
# datasets/paper-rig (identify --html), the diagnose report of
# datasets/hidden/valve-lag (diagnose --html) and the fleet report of
# datasets/fleet (batch --html). Each page checks its own plots (every canvas
# drew) and catches its own errors, writing the outcome into
# #pneumaid-status, which is read from --dump-dom; a PNG screenshot of each is
# saved beside it for people to look at.
#   scripts/report-check.sh [BUILD_DIR]     (writes BUILD_DIR/report-check/)
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
out="$build/report-check"
rm -rf "$out"
mkdir -p "$out"
pneumaid="$build/pneumaid"
"$pneumaid" identify datasets/paper-rig --out "$out/paper-rig.yaml" \
  --html "$out/paper-rig.html" >/dev/null
"$pneumaid" diagnose --params configs/paper.yaml datasets/hidden/valve-lag \
  --out "$out/diagnose-valve-lag" --threads "$(nproc)" --html "$out/diagnose-valve-lag.html" \
  >/dev/null
# The fleet holds a corrupt unit: batch exits 3 and the page lists it.
status=0
"$pneumaid" batch datasets/fleet --out "$out/fleet-results" -j "$(nproc)" \
  --html "$out/fleet.html" >/dev/null 2>&1 || status=$?
[ "$status" -eq 3 ] || { echo "report check: batch exited $status, expected 3"; exit 1; }

flags=(--headless --no-sandbox --disable-gpu --hide-scrollbars --virtual-time-budget=10000
       --no-first-run --disable-background-networking --disable-component-update --disable-sync)
failed=0
for page in paper-rig diagnose-valve-lag fleet; do
  url="file://$(pwd)/$out/$page.html"
  status=$(timeout 120 chromium "${flags[@]}" --dump-dom "$url" 2>/dev/null |
           grep -o '<div id="pneumaid-status"[^<]*</div>' || true)
  timeout 120 chromium "${flags[@]}" --window-size=1280,3000 --screenshot="$out/$page.png" \
    "$url" >/dev/null 2>&1 || true
  echo "report check: $page: ${status:-no status element} (screenshot $out/$page.png)"
  case "$status" in *'class="ok"'*) ;; *) failed=1 ;; esac
done
exit "$failed"
