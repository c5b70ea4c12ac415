#!/usr/bin/env bash
# Refreshes the vendored uPlot (the charting library of the HTML reports) from
# the npm registry at a pinned version: its minified script, its stylesheet
# and its licence go to src/report/vendor/uplot/, which the build embeds in the
# binary (reports are self-contained: no network reference).
#   scripts/vendor-uplot.sh [VERSION]     (default: the pinned one below)
set -euo pipefail
cd "$(dirname "$0")/.."
version=${1:-1.6.32}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
(cd "$work" && npm pack "uplot@$version" --silent >/dev/null 2>&1)
tar -xzf "$work/uplot-$version.tgz" -C "$work"
target=src/report/vendor/uplot
mkdir -p "$target"
cp "$work/package/dist/uPlot.iife.min.js" "$work/package/dist/uPlot.min.css" "$target/"
cp "$work/package/LICENSE" "$target/LICENSE"
echo "$version" > "$target/VERSION"
echo "vendored uPlot $version into $target"
