#!/usr/bin/env bash
# The main job on the bundled data. Today: simulate the seed paper's
# full-stroke step (u = +1 from the retracted end) with configs/paper.yaml and
# summarise it. Identification and validation on datasets/ land with the
# identification issue.
set -euo pipefail
cd "$(dirname "$0")/.."

scripts/setup.sh >/dev/null
mkdir -p out
build/pneumaid simulate --params configs/paper.yaml --step 1@0 --until 1.5 --rate 1000 \
  --out out/paper-step.csv
