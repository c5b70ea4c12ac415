#!/usr/bin/env bash
# The main job on the bundled data, as far as the toolkit goes today: check the
# bundled unit datasets/paper-rig (synthetic), then simulate its validation runs
# with the paper's parameter set from their logged commands and first samples.
# Identification and validation proper land with the identification issue.
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/setup.sh >/dev/null
pneumaid=build/pneumaid
mkdir -p out

echo "== pneumaid check datasets/paper-rig"
$pneumaid check datasets/paper-rig
for run in step-1 profile-1; do
  echo "== pneumaid simulate --params configs/paper.yaml --input datasets/paper-rig/$run.csv"
  $pneumaid simulate --params configs/paper.yaml --input "datasets/paper-rig/$run.csv" \
    --out "out/paper-rig-$run-sim.csv"
done
