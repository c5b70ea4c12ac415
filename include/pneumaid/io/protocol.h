// Test protocols of the synthetic rig (`pneumaid-protocol/1`, see
// docs/synthetic-rig.md): which experiments to run, how the instruments
// behave, and in which units the rig writes its logs.
#pragma once

#include <map>
#include <string>
#include <utility>
#include <vector>

#include "pneumaid/io/rig_data.h"

namespace pneumaid {

inline constexpr const char* kProtocolFormat = "pneumaid-protocol/1";

// One instrument (a CSV column). All SI (flows: standard volumetric m3/s).
struct SensorModel {
  double sigma = 0.0;         // Gaussian noise std
  double tau_s = 0.0;         // first-order lag
  double quantization = 0.0;  // ADC step (0 = none)
  bool declared = true;       // written to the manifest's sensors block
};

struct Protocol {
  double sample_rate_Hz = 1000.0;
  // The share of rows a lossy logger drops from the stroke and validation
  // logs (independently per row, never the first or last): their sampling is
  // then not uniform.
  double dropped_samples = 0.0;
  // A logger whose clock is irregular: each interval between two rows is the
  // nominal one (1 / sample_rate_Hz) times 1 + U(-clock_jitter, clock_jitter),
  // stamped to 10 us, in every log; each row holds the signals at its own
  // time, and the command changes at rows only. In [0, 0.5); 0: uniform.
  double clock_jitter = 0.0;
  PositionOrigin position_origin = PositionOrigin::kRetracted;
  std::string length_unit = "mm";
  std::string pressure_unit = "bar_g";
  std::string flow_unit = "l/min";
  std::map<std::string, SensorModel> sensors;  // by column name

  // Valve test: staircase 0 -> 1 -> 0 in steps of valve_step_V held
  // valve_hold_s; or, when valve_ramp_s > 0, a ramp 0 -> 1 V over valve_ramp_s
  // and back down over as long (a continuous command, no plateaus); or, when
  // valve_levels_V is given, those commands in order, each held valve_hold_s
  // (as listed: 0 V between levels makes a staircase that returns to 0 V).
  bool valve = false;
  double valve_step_V = 0.05;
  double valve_hold_s = 0.3;
  double valve_ramp_s = 0.0;
  std::vector<double> valve_levels_V;

  // Pipeline tests: a step to pipeline_command_V at pipeline_step_time_s, per
  // tube length; or, when pipeline_schedule is given, the command held at
  // each (time [s], level [V]) knot from its time on (0 V before the first).
  std::vector<double> tube_lengths_m;
  double pipeline_command_V = 1.0;
  double pipeline_step_time_s = 0.1;
  double pipeline_duration_s = 1.5;
  std::vector<std::pair<double, double>> pipeline_schedule;

  // Stroke tests: per level, extend until stroke_margin_m before the end, then
  // retract; stroke_cycles such cycles in each level's log.
  std::vector<double> stroke_levels_V;
  int stroke_cycles = 1;
  double stroke_margin_m = 1e-3;
  double stroke_max_leg_s = 3.0;
  // Each leg goes on this long after the rod reached `margin` before the end
  // (with margin 0: the rod is pushed into the end stop).
  double stroke_dwell_s = 0.0;

  // How the rig's physics differs from the model the fits use (none by
  // default): a real rig is not the fitting model.
  struct Mismatch {
    // Stick as a smooth law (creep below stick_velocity) instead of events:
    // the catalog's stick_creep effect at that width (a truth holding the
    // effect creeps at its own v).
    bool regularized_friction = false;
    double stick_velocity_m_per_s = 1e-4;
    // The rig's integration tolerance (the fits use 1e-5 to 1e-6).
    double relative_tolerance = 1e-6;
  } mismatch;

  // Validation runs.
  bool paper_step = false;    // u = +1 then -1, each until 1 mm before the stroke limit
  bool rich_profile = false;  // steps of several amplitudes and slow ramps
};

// Parses a protocol (strict keys; InputError with line and column).
Protocol ParseProtocol(const std::string& text, const std::string& source);
Protocol LoadProtocol(const std::string& path);

}  // namespace pneumaid
