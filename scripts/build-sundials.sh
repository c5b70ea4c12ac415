#!/usr/bin/env bash
# Builds an optimised CVODES from Debian 12's own source package of libsundials
# (the same 6.4.1+dfsg1 that libsundials-dev ships) into .deps/sundials.
#
# Why: Debian's binary is compiled without optimisation (its debian/rules passes
# -DCMAKE_C_FLAGS=-fcommon, which replaces dpkg's -O2), and the CVODE core is
# then half of a simulation's time (docs/performance.md). Same source, same
# version, -O2: simulations run about twice as fast.
#
# Idempotent: does nothing when .deps/sundials is already built. When the
# source cannot be fetched (no network), it says so and exits 0: CMake then
# links Debian's binary, which gives the same results, only slower.
set -euo pipefail
cd "$(dirname "$0")/.."

VERSION=6.4.1+dfsg1
TARBALL=sundials_${VERSION}.orig.tar.xz
# From Debian bookworm's Sources index (Checksums-Sha256 of package sundials).
SHA256=c61157f1d4be06c704bea40cb131eb63ba2dada161989071604d0a0959cdf04a
URL=${PNEUMAID_SUNDIALS_URL:-http://deb.debian.org/debian/pool/main/s/sundials/${TARBALL}}
PREFIX=$PWD/.deps/sundials
STAMP=$PREFIX/.built-${VERSION}

[ -f "$STAMP" ] && exit 0
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT

if ! command -v curl >/dev/null || ! command -v xz >/dev/null; then
  echo "build-sundials: curl or xz missing; using Debian's unoptimised libsundials" >&2
  exit 0
fi
if ! curl -fsS --max-time 120 "$URL" -o "$WORK/$TARBALL"; then
  echo "build-sundials: could not fetch $URL; using Debian's unoptimised libsundials" >&2
  exit 0
fi
echo "$SHA256  $WORK/$TARBALL" | sha256sum -c --quiet - || {
  echo "build-sundials: checksum mismatch for $TARBALL" >&2
  exit 1
}
mkdir "$WORK/src"
tar xf "$WORK/$TARBALL" -C "$WORK/src" --strip-components=1
cmake -S "$WORK/src" -B "$WORK/build" -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_INSTALL_PREFIX="$PREFIX" -DCMAKE_POSITION_INDEPENDENT_CODE=ON \
  -DBUILD_SHARED_LIBS=OFF -DBUILD_STATIC_LIBS=ON \
  -DBUILD_ARKODE=OFF -DBUILD_CVODE=OFF -DBUILD_CVODES=ON -DBUILD_IDA=OFF -DBUILD_IDAS=OFF \
  -DBUILD_KINSOL=OFF -DBUILD_FORTRAN_MODULE_INTERFACE=OFF \
  -DEXAMPLES_ENABLE_C=OFF -DEXAMPLES_ENABLE_CXX=OFF -DEXAMPLES_INSTALL=OFF >"$WORK/log" 2>&1 &&
  cmake --build "$WORK/build" -j"$(nproc)" >>"$WORK/log" 2>&1 &&
  rm -rf "$PREFIX" && cmake --install "$WORK/build" >>"$WORK/log" 2>&1 || {
  tail -40 "$WORK/log" >&2
  echo "build-sundials: building CVODES failed (log above)" >&2
  exit 1
}
touch "$STAMP"
echo "build-sundials: optimised CVODES $VERSION installed in $PREFIX"
