#!/usr/bin/env bash
# The discrepancy workflow's studies (docs/diagnose.md), on synthetic units
# with the rig's model mismatch, validation runs only (configs/protocol-validation.yaml with
# stick events: its smooth stick, a rod that creeps, is the catalog's stick_creep, studied as
# an effect of its own):
#   scripts/diagnose-study.sh false-positives [SEEDS]   # clean units, both orientations
#   scripts/diagnose-study.sh detection [SEED [EFFECT]] # each effect (or one) at four sizes
# Prints one line per unit: what was hidden, what diagnose named.
set -euo pipefail
cd "$(dirname "$0")/.."
[ -x build/pneumaid ] || scripts/setup.sh >/dev/null
pneumaid=build/pneumaid
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
sed 's/friction: regularized/friction: events/' configs/protocol-validation.yaml \
  > "$work/protocol.yaml"
grep -q 'friction: events' "$work/protocol.yaml" || { echo "protocol: no stick events" >&2; exit 1; }

run() {  # label, truth config, effects body, seed, base config
  local label=$1 truth=$2 effects=$3 seed=$4 base=$5
  sed "s/^effects: {}/effects: {$effects}/" "$truth" > "$work/truth.yaml"
  rm -rf "$work/unit" "$work/out"
  $pneumaid synth --truth "$work/truth.yaml" --protocol "$work/protocol.yaml" \
    --seed "$seed" --out "$work/unit" >/dev/null
  local named
  named=$($pneumaid diagnose --params "$base" "$work/unit" --out "$work/out" --max-effects 1 \
            --threads "$(nproc)" --json "$work/r.json" >/dev/null &&
          python3 -c "import json; r=json.load(open('$work/r.json')); print(','.join(r['named_effects']) or '-')")
  printf '%-44s seed %-4s named: %s\n' "$label" "$seed" "$named"
}

case "${1:-false-positives}" in
  false-positives)
    seeds=${2:-10}
    for config in paper.yaml paper-horizontal.yaml; do
      for seed in $(seq 1 "$seeds"); do
        run "clean ${config%.yaml}" "configs/$config" "" "$((300 + seed))" "configs/$config"
      done
    done
    ;;
  detection)
    seed=${2:-401}
    only=${3:-}
    while read -r effect parameter sizes; do
      [ -z "$only" ] || [ "$only" = "$effect" ] || continue
      for size in $sizes; do
        if [ "$effect" = pipeline_lag ]; then
          sed "s/^  delta: 8.0/  delta: $size/" configs/paper.yaml > "$work/paper-delta.yaml"
          run "pipeline_lag delta $size (base: no tube lag)" "$work/paper-delta.yaml" "" "$seed" \
            configs/paper-no-tube.yaml
        else
          run "$effect $parameter $size" configs/paper.yaml "$effect: {$parameter: $size}" "$seed" \
            configs/paper.yaml
        fi
      done
    done <<'EOT'
valve_lag tau 0.005 0.01 0.02 0.04
flow_sensor_lag tau 0.01 0.02 0.04 0.08
pipeline_lag delta 30 15 8 4
cross_leakage c 2.5e-12 5e-12 1e-11 2e-11
heat_transfer h 0.0125 0.025 0.05 0.1
supply_droop r 6e7 1.2e8 2.5e8 5e8
friction_pressure kp 2.5e-7 5e-7 1e-6 2e-6
valve_deadzone u0 0.01 0.02 0.04 0.08
stick_creep v 2.5e-5 5e-5 1e-4 2e-4
EOT
    ;;
  *) echo "usage: $0 false-positives [SEEDS] | detection [SEED [EFFECT]]" >&2; exit 2 ;;
esac
