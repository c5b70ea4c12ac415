#!/usr/bin/env bash
# The main job on the bundled data: check the bundled unit datasets/paper-rig
# (synthetic), identify it (today: the valve's K_vp and the tube lag delta; the
# friction fit is still to come and is taken from the prior, configs/paper.yaml,
# as the report says), then validate the identified set on
# the unit's validation runs. Results go to out/.
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/setup.sh >/dev/null
pneumaid=build/pneumaid
mkdir -p out

echo "== pneumaid check datasets/paper-rig"
$pneumaid check datasets/paper-rig
echo "== pneumaid identify datasets/paper-rig --out out/paper-rig.yaml"
$pneumaid identify datasets/paper-rig --out out/paper-rig.yaml
echo "== pneumaid validate --params out/paper-rig.yaml datasets/paper-rig"
$pneumaid validate --params out/paper-rig.yaml datasets/paper-rig \
  --json out/paper-rig-validation.json --csv-out out/paper-rig-validation
echo "results: out/paper-rig.yaml, out/paper-rig-validation.json, out/paper-rig-validation/*.csv"
