#!/usr/bin/env bash
# The install test (issue 14): cmake --install into a temporary prefix, the
# installed binary run from another directory with its own defaults (prior and
# fit spec under share/pneumaid/configs), and a consumer program built against
# the installed CMake package. Usage: tests/install/run.sh BUILD_DIR
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=$(cd "${1:-$root/build}" && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" >/dev/null
cd "$work"
# Its defaults are the installed configs, not the source tree's.
"$work/prefix/bin/pneumaid" identify --help | grep -q "$work/prefix/share/pneumaid/configs/paper.yaml"
"$work/prefix/bin/pneumaid" identify "$root/datasets/paper-rig" --out identified.yaml >/dev/null
grep -q "friction:" identified.yaml
"$work/prefix/bin/pneumaid" export --params identified.yaml --format ros2 >/dev/null
cmake -S "$root/tests/install/consumer" -B consumer -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build consumer -j"$(nproc)" >/dev/null
./consumer/consumer
echo "install test: passed (prefix $work/prefix)"
