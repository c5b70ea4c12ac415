#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (+ AddressSanitizer, UBSan) into
# build-fuzz/ and runs each for SECONDS (default 60) from the seed corpus in
# tests/fuzz/corpus/ (copied, so the tree is not changed).
#   scripts/fuzz.sh [SECONDS]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
scripts/setup.sh >/dev/null  # the Debian packages
command -v clang++ >/dev/null || { apt-get update -qq && apt-get install -y -qq clang libclang-rt-14-dev >/dev/null; }
CXX=clang++ CC=clang cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPNEUMAID_FUZZ=ON \
  -DPNEUMAID_BUILD_TESTS=OFF -DPNEUMAID_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build build-fuzz -j"$(nproc)" --target csv_fuzz manifest_fuzz
for target in csv manifest; do
  work=$(mktemp -d)
  cp tests/fuzz/corpus/$target/* "$work/"
  echo "fuzzing $target for $seconds s"
  build-fuzz/tests/fuzz/${target}_fuzz -max_total_time="$seconds" -max_len=4096 "$work" 2>&1 | tail -3
  rm -rf "$work"
done
