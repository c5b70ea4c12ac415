#!/usr/bin/env bash
# Issue 12's robustness sweep: N seeded synthetic units (truths, protocols and
# model mismatch drawn across a fleet's ranges; every unit is synthetic, made
# by pneumaid's synthetic rig from the seed), each identified, refined and
# validated; prints per coefficient the share within tolerance.
#   scripts/sweep.sh N [--seed S] [--jobs J] [--min-units K] [--keep DIR]
#                      [--start identify|truth] [--held-out-probe K] ...
# (every flag of tests/bench/robustness_sweep.cpp, passed through)
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 1 ] || { echo "usage: scripts/sweep.sh N [--seed S] [--jobs J] [--min-units K] [--keep DIR] [--start identify|truth] [--held-out-probe K]" >&2; exit 2; }
scripts/setup.sh >/dev/null
exec build/tests/bench/robustness_sweep "$@"
