#!/usr/bin/env bash
# The full test suite: installs what is missing, builds Release and runs every
# test with CTest. Then the same suite built with AddressSanitizer and
# UndefinedBehaviorSanitizer (skip with PNEUMAID_SKIP_SANITIZERS=1).
set -euo pipefail
cd "$(dirname "$0")/.."

# Each phase's wall time, so that a slow CI run shows where its minutes went
# (the brief: keep .ci/run under 40 minutes).
phase_start=$SECONDS
elapsed() { echo "$((SECONDS / 60)) min $((SECONDS % 60)) s"; }
phase() {
  echo "test.sh: $1 took $((SECONDS - phase_start)) s (at $(elapsed))"
  phase_start=$SECONDS
}
# Also when a phase fails or the run is stopped: how long it had run.
trap 'echo "test.sh: exit status $? at $(elapsed), $((SECONDS - phase_start)) s into the last phase"' EXIT

# Issue 12's redesign: no file in src/ident/ over 500 lines.
long=$(find src/ident -name '*.cpp' -o -name '*.h' | xargs wc -l | awk '$2 != "total" && $1 > 500')
if [ -n "$long" ]; then
  echo "files in src/ident/ over 500 lines (issue 12): $long" >&2
  exit 1
fi

# openmpi-bin: the batch test launches `mpirun -n 2 pneumaid batch --shard auto`;
# chromium: the report's own check in a headless browser (Release pass only).
EXTRA_PACKAGES="openmpi-bin chromium" scripts/setup.sh
phase "setup (packages, CVODES, Release build)"
ctest --test-dir build --output-on-failure -j"$(nproc)"
phase "Release tests"
# Installation: cmake --install, the installed binary with its own defaults, a
# consumer program built against the installed package.
tests/install/run.sh build
scripts/report-check.sh build
phase "install test and report check"
# Issue 12's robustness sweep, 6 seeded units with model mismatch and drawn
# protocols (Release only, 2 to 3.5 min on 2 cores): gates on K_vp and delta
# within tolerance on at least 5 of 6 units; the friction shares are printed
# (not yet at issue 12's target: docs/identification.md).
build/tests/bench/robustness_sweep 6 --seed 2026 --jobs "$(nproc)" --min-units-valve-tube 5
phase "6-unit robustness gate"

if [ "${PNEUMAID_SKIP_SANITIZERS:-0}" != 1 ]; then
  BUILD_DIR=build-asan CMAKE_ARGS="-DPNEUMAID_SANITIZE=ON -DPNEUMAID_BUILD_BENCHMARKS=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo" \
    scripts/setup.sh
  phase "sanitizer build"
  # The multi-second statistical recovery tests (many seeds, multistart, whole
  # refinements) run in the Release pass only: under the sanitizers they take
  # minutes each and exercise no code path that the other tests leave out.
  SLOW='StandardErrorsAreHonestOverTenSeeds|HalvesTheHeldOutPositionError'
  SLOW+='|MultistartKeepsTheBest|FromTrajectoriesAloneStartingThirtyPercentOff'
  SLOW+='|RecoversAHorizontalCylindersFriction|RecoversTheTenDefaultParametersFromTheComponentFits'
  # Diagnose: one run under the sanitizers (the cross-leakage unit), the rest
  # in the Release pass.
  SLOW+='|ClosesMostOfItsGap/(ValveLag|FlowSensorLag|PipelineLag|HeatTransfer|SupplyDroop|FrictionPressure|ValveDeadzone|StickCreep)'
  SLOW+='|NamesNothingOnCleanUnits|SlightlyOffBaseCoefficients|NamesTwoHiddenEffects'
  SLOW+='|TellsAValveLagFromAFlowMeterLag|ValidatesAndDiagnosesEachUnitWhenAsked'
  # Whole batch processes with refinement, killed and resumed: process-level
  # behaviour the Release pass checks; the resume path's code runs in BatchTest.
  SLOW+='|AKilledRunResumesToTheSameResults'
  # The windows' screen (three searches, ~3 800 simulations in all) and the
  # fits by windows first, each test of them: under the sanitizers one whole
  # refinement runs them all (TheVerdictTellsAnExplainedUnitFromOneWithAMissingEffect:
  # both screens, the profiled search, 3 next-best candidates fitted, by
  # windows first where not explained). FromBiasedComponentFits... took 444 s
  # there (session 29); the fresh-clone CI took 40.5 min with it excluded.
  SLOW+='|TheScreenRankedByWindowsFindsTheSameBasin|RankedByWindowsTheJointSearchMovesFdAndBToo|TheProfiledSearchRanksNearTheTruth'
  SLOW+='|RankedByWindowsTheScreenFindsEachDirectionsBasin|ALightRodLoggedAt500HzIsFoundByMultipleShooting'
  SLOW+='|FromBiasedComponentFitsItSaysWhenTheRunsAreNotExplained'
  # The friction fit's replays of every stop of many strokes (11 s in
  # Release); the stop segments' code runs in the other friction tests.
  SLOW+='|AnFsTheMidStrokeSlidesLeaveOpenIsReadAtTheStops'
  # identify --refine of the bundled unit with the creep fit (11 s in Release,
  # five more fits of the last stage); the creep fit runs under the sanitizers
  # in RefineCreepTest, identify --refine in RefineCliTest.
  SLOW+='|AUnitWithoutDeclaredNoiseIsIdentifiedAndRefined'
  ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
    ctest --test-dir build-asan --output-on-failure -j"$(nproc)" -E "$SLOW"
  phase "sanitizer tests"
fi

# ThreadSanitizer: the library and the batch test alone (units identified on
# worker threads, compared with one thread's results); skip with
# PNEUMAID_SKIP_TSAN=1.
if [ "${PNEUMAID_SKIP_TSAN:-0}" != 1 ]; then
  cmake -S . -B build-tsan -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPNEUMAID_TSAN=ON \
    -DPNEUMAID_BUILD_BENCHMARKS=OFF >/dev/null
  cmake --build build-tsan -j"$(nproc)" --target batch_test >/dev/null
  TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" \
    build-tsan/tests/batch_test --gtest_filter='BatchTest.ThreadsGiveWhatOneThreadGives:BatchTest.ATimeLimitStopsAUnitsWorkAndRecordsWhy'
  phase "ThreadSanitizer build and batch test"
fi

