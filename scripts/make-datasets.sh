#!/usr/bin/env bash
# Regenerates datasets/ from the synthetic rig. Every unit in it is synthetic
# (made by `pneumaid synth` from configs/paper.yaml), not measured.
#   scripts/make-datasets.sh           # rewrites datasets/paper-rig and datasets/fleet
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh >/dev/null
pneumaid=build/pneumaid

rm -rf datasets/paper-rig datasets/fleet
mkdir -p datasets/fleet

# One unit with the seed paper's parameters and the full protocol.
$pneumaid synth --truth configs/paper.yaml --protocol configs/protocol-full.yaml --seed 1 \
  --unit paper-rig --out datasets/paper-rig

# A fleet: 12 units with manufacturing spread, one clear outlier, one corrupt log.
spread=(--spread 'valve.*.q_max=0.05' --spread 'friction.*.*=0.15' --spread 'pipeline.delta=0.10')
for i in $(seq -w 1 12); do
  $pneumaid synth --truth configs/paper.yaml --protocol configs/protocol-fleet.yaml --seed "1$i" \
    --unit "PVQ13-00$i" "${spread[@]}" --out "datasets/fleet/PVQ13-00$i"
done
# Outlier: a worn seal, three times the static friction of a new one.
$pneumaid synth --truth configs/paper.yaml --protocol configs/protocol-fleet.yaml --seed 113 \
  --unit PVQ13-0013 "${spread[@]}" --scale friction.positive.Fs=3 --scale friction.negative.Fs=3 \
  --out datasets/fleet/PVQ13-0013
# Corrupt: a logger that lost the end of a line (a ragged last row).
$pneumaid synth --truth configs/paper.yaml --protocol configs/protocol-fleet.yaml --seed 114 \
  --unit PVQ13-0014 "${spread[@]}" --out datasets/fleet/PVQ13-0014
printf '1.7,0.5,12.3\n' >> datasets/fleet/PVQ13-0014/step-1.csv
echo "datasets regenerated"
