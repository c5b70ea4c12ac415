#!/usr/bin/env bash
# The main job on the bundled data, as far as the toolkit goes today: check the
# bundled unit datasets/paper-rig (synthetic), then validate the seed paper's
# parameter set on its validation runs (each simulated from its logged command
# and first sample, compared channel by channel). Reports go to out/.
# Identification (fitting the set from the unit's logs first) lands with the
# identification issue.
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/setup.sh >/dev/null
pneumaid=build/pneumaid
mkdir -p out

echo "== pneumaid check datasets/paper-rig"
$pneumaid check datasets/paper-rig
echo "== pneumaid validate --params configs/paper.yaml datasets/paper-rig"
$pneumaid validate --params configs/paper.yaml datasets/paper-rig \
  --json out/paper-rig-validation.json --csv-out out/paper-rig-validation
echo "reports: out/paper-rig-validation.json, out/paper-rig-validation/*.csv"
