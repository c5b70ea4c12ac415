#!/usr/bin/env bash
# The main job on the bundled data: check the bundled unit datasets/paper-rig
# (synthetic), identify it (the valve's K_vp, the tube lag delta, Stribeck
# friction per direction), validate the identified set on the unit's
# validation runs, refine it through the simulator on the stroke logs
# (configs/fit-default.yaml, about 10-20 s) and validate the refined set.
# Then the discrepancy workflow on datasets/hidden/valve-lag (a unit whose
# rig has a valve lag the paper's model lacks). Results go to out/.
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/setup.sh >/dev/null
pneumaid=build/pneumaid
mkdir -p out

echo "== pneumaid check datasets/paper-rig"
$pneumaid check datasets/paper-rig
echo "== pneumaid identify datasets/paper-rig --out out/paper-rig.yaml"
$pneumaid identify datasets/paper-rig --out out/paper-rig.yaml --html out/paper-rig.html
echo "== pneumaid validate --params out/paper-rig.yaml datasets/paper-rig"
$pneumaid validate --params out/paper-rig.yaml datasets/paper-rig \
  --json out/paper-rig-validation.json --csv-out out/paper-rig-validation
echo "== pneumaid refine datasets/paper-rig --params out/paper-rig.yaml --out out/paper-rig-refined.yaml"
$pneumaid refine datasets/paper-rig --params out/paper-rig.yaml --out out/paper-rig-refined.yaml \
  --html out/paper-rig-refined.html
echo "== pneumaid validate --params out/paper-rig-refined.yaml datasets/paper-rig"
$pneumaid validate --params out/paper-rig-refined.yaml datasets/paper-rig \
  --json out/paper-rig-refined-validation.json
echo "== pneumaid diagnose --params configs/paper.yaml datasets/hidden/valve-lag --out out/diagnose-valve-lag"
$pneumaid diagnose --params configs/paper.yaml datasets/hidden/valve-lag --out out/diagnose-valve-lag \
  --threads "$(nproc)" --html out/diagnose-valve-lag.html
echo "results: out/paper-rig.yaml (component fits), out/paper-rig-refined.yaml (refined),"
echo "  out/paper-rig-validation.json, out/paper-rig-refined-validation.json,"
echo "  out/paper-rig-validation/*.csv, out/diagnose-valve-lag/ (report.md, params.yaml, CSVs);"
echo "  reports to open in a browser: out/paper-rig.html, out/paper-rig-refined.html,"
echo "  out/diagnose-valve-lag.html"
