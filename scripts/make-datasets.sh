#!/usr/bin/env bash
# Regenerates datasets/ from the synthetic rig. Every unit in it is synthetic
# (made by `pneumaid synth` from configs/paper.yaml), not measured.
#   scripts/make-datasets.sh           # rewrites datasets/paper-rig, fleet and hidden
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh >/dev/null
pneumaid=build/pneumaid

rm -rf datasets/paper-rig datasets/fleet datasets/hidden
mkdir -p datasets/fleet datasets/hidden

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

# Hidden effects for the discrepancy workflow: validation runs only (the
# paper's step, the rich profile, flows logged), the rig's mismatch on.
# Each unit's truth is configs/paper.yaml (or paper-horizontal.yaml) with the
# effect below; diagnose it with configs/paper.yaml (paper-no-tube.yaml for
# pipeline_lag: the seed paper's story of a model without the tube lag).
hidden() {  # name, effects (YAML flow map body), seed, truth config, base config
  local name=$1 effects=$2 seed=$3 truth=${4:-configs/paper.yaml} base=${5:-configs/paper.yaml}
  local truth_file
  truth_file=$(mktemp)
  sed "s/^effects: {}/effects: {$effects}/" "$truth" > "$truth_file"
  $pneumaid synth --truth "$truth_file" --protocol configs/protocol-validation.yaml --seed "$seed" \
    --unit "hidden-$name" --out "datasets/hidden/$name" >/dev/null
  rm -f "$truth_file"
  local what="nothing (a clean unit: the model mismatch of the rig and sensor noise only)"
  [ -n "$effects" ] && what=$effects
  cat > "datasets/hidden/$name/README.md" <<EOT
# hidden/$name (synthetic)

Made by \`scripts/make-datasets.sh\`:
\`pneumaid synth --truth <$truth with effects: {$effects}> --protocol configs/protocol-validation.yaml --seed $seed\`.

Hidden: $what.
Validation runs only (step-1, profile-1), flows logged, smooth stick and tighter integration in
the rig (model mismatch). \`truth.yaml\` holds the truth; no fitter reads it.

Diagnose with: \`pneumaid diagnose --params $base datasets/hidden/$name --out OUT\`
EOT
}
hidden valve-lag "valve_lag: {tau: 0.03}" 201
hidden flow-sensor-lag "flow_sensor_lag: {tau: 0.08}" 202
hidden pipeline-lag "" 203 configs/paper.yaml configs/paper-no-tube.yaml
hidden cross-leakage "cross_leakage: {c: 2.0e-11}" 204
hidden heat-transfer "heat_transfer: {h: 0.05}" 205
hidden supply-droop "supply_droop: {r: 5.0e8}" 206
hidden friction-pressure "friction_pressure: {kp: 2.0e-6}" 207
hidden valve-deadzone "valve_deadzone: {u0: 0.08}" 208
hidden two-effects "valve_lag: {tau: 0.03}, cross_leakage: {c: 2.0e-11}" 209
hidden clean-vertical "" 210
hidden clean-horizontal "" 211 configs/paper-horizontal.yaml configs/paper-horizontal.yaml
sed -i '/^Hidden: nothing/d' datasets/hidden/pipeline-lag/README.md
cat >> datasets/hidden/pipeline-lag/README.md <<EOT

Hidden: the seed paper's tube lag itself (Eq. 5, delta 8 1/s): the truth is configs/paper.yaml,
the model diagnosed is configs/paper-no-tube.yaml (\`pipeline.model: none\`).
EOT
echo "datasets regenerated"
