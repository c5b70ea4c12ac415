#!/usr/bin/env bash
# Installs what is missing (Debian 12 packages only), configures and builds
# Release into build/. Idempotent: a second run installs nothing and rebuilds
# only what changed.
#   BUILD_DIR=...      build directory (default: build)
#   CMAKE_ARGS="..."   extra configure arguments
#   EXTRA_PACKAGES="..." Debian packages the caller needs too (test.sh: openmpi-bin)
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(build-essential cmake libeigen3-dev libceres-dev libsundials-dev libyaml-cpp-dev
          googletest libgtest-dev libcli11-dev libbenchmark-dev curl xz-utils)
# shellcheck disable=SC2206
PACKAGES+=(${EXTRA_PACKAGES:-})
missing=()
for package in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" ||
    missing+=("$package")
done
if ((${#missing[@]})); then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi

# An optimised build of Debian's own SUNDIALS source (why: scripts/build-sundials.sh).
scripts/build-sundials.sh

BUILD_DIR=${BUILD_DIR:-build}
# shellcheck disable=SC2086
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release ${CMAKE_ARGS:-} >/dev/null
cmake --build "$BUILD_DIR" -j"$(nproc)"
