#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "../io/parse_number.h"
#include "commands.h"
#include "pneumaid/eval/stroke_summary.h"
#include "pneumaid/io/csv_table.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/json.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/io/trajectory_csv.h"
#include "pneumaid/io/units.h"
#include "pneumaid/sim/simulate.h"
#include "pneumaid/validate/logged_run.h"
#include "pneumaid/validate/validate.h"

namespace pneumaid::cli {
namespace {

struct SimulateArgs {
  std::string params_path;
  std::vector<std::string> steps;  // "U@T0"
  std::string input_path;
  double until_s = NAN;
  double rate_Hz = 1000.0;
  bool rate_given = false;
  std::string out_path;
};

// "U@T0" -> (T0, U).
std::pair<double, double> ParseStep(const std::string& text) {
  const auto at = text.find('@');
  try {
    if (at == std::string::npos) throw std::invalid_argument("no @");
    double u = 0, t = 0;
    const char* const stop = text.c_str() + text.size();
    // Locale-independent, as every reader of pneumaid.
    const char* u_end = internal::ParseNumber(text.c_str(), text.c_str() + at, &u);
    const char* t_end = internal::ParseNumber(text.c_str() + at + 1, stop, &t);
    if (u_end != text.c_str() + at || at == 0 || t_end != stop || at + 1 == text.size() ||
        !std::isfinite(u) || !std::isfinite(t) || std::fabs(u) > 1) {
      throw std::invalid_argument("bad number");
    }
    return {t, u};
  } catch (const std::logic_error&) {
    throw InputError("--step", 0, 0,
                     "'" + text + "': expected U@T0 with U in [-1, 1] V and T0 in s, e.g. 1@0");
  }
}

// Column `name` of a log in SI, or empty when absent.
std::vector<double> ColumnInSI(const CsvTable& table, const std::string& name, Quantity quantity,
                               double atmospheric_pressure_Pa, bool required) {
  const CsvColumn* column = table.Find(name);
  if (column == nullptr) {
    if (required)
      throw InputError(table.file, table.header_line, 0, "missing column '" + name + "'");
    return {};
  }
  const UnitInfo* unit = column->unit.empty() ? nullptr : FindUnit(column->unit);
  if (!column->unit.empty() && (unit == nullptr || unit->quantity != quantity)) {
    throw InputError(table.file, table.header_line, column->column,
                     "column '" + name + "': unit '" + column->unit + "' not accepted; expected " +
                         AcceptedUnits({quantity}));
  }
  std::vector<double> values = column->values;
  if (unit != nullptr) {
    for (double& value : values) value = ToSI(*unit, value, atmospheric_pressure_Pa);
  }
  return values;
}

struct LoggedRun {
  CommandSignal command;
  std::vector<double> t_s;
  InitialState initial;
};

// The command of a log outside a unit directory (and its first state, when
// the log has x, p1, p2), taken as pneumaid writes logs (SI, x from
// mid-stroke, mass flows).
LoggedRun ReadLoggedRun(const std::string& path, const Parameters& params) {
  std::map<std::string, std::vector<double>> columns;
  const CsvTable table = ReadCsv(path);
  const double p_atm = params.supply.atmospheric_pressure_Pa;
  columns["t"] = ColumnInSI(table, "t", Quantity::kTime, p_atm, true);
  columns["u"] = ColumnInSI(table, "u", Quantity::kCommand, p_atm, true);
  columns["x"] = ColumnInSI(table, "x", Quantity::kLength, p_atm, false);
  columns["p1"] = ColumnInSI(table, "p1", Quantity::kPressure, p_atm, false);
  columns["p2"] = ColumnInSI(table, "p2", Quantity::kPressure, p_atm, false);
  // The format's check of a wrong origin: with no manifest to say it, x is
  // from mid-stroke, and the set's stroke is the stroke.
  const double half_m = 0.5 * params.cylinder.stroke_m;
  for (std::size_t i = 0; i < columns["x"].size(); ++i) {
    if (std::fabs(columns["x"][i]) > half_m + 1e-3) {
      throw InputError(path, table.row_lines[i], table.Find("x")->column,
                       "column 'x': position " + FormatSignificant(columns["x"][i] * 1e3, 6) +
                           " mm is more than 1 mm outside the stroke; a log outside a unit "
                           "directory is read with x from mid-stroke (as pneumaid writes logs)");
    }
  }
  for (std::size_t i = 1; i < columns["t"].size(); ++i) {
    if (!(columns["t"][i] > columns["t"][i - 1])) {
      throw InputError(path, table.row_lines[i], 1,
                       "column 't': expected strictly increasing time");
    }
  }
  LoggedRun run;
  run.t_s = columns["t"];
  Trajectory logged;
  logged.t_s = run.t_s;
  logged.u_V = columns["u"];
  if (!columns["x"].empty() && !columns["p1"].empty() && !columns["p2"].empty()) {
    // As validation starts a logged run (a rod on its stop reads a little
    // beyond it: clamped to the stroke).
    logged.x_m = columns["x"];
    logged.p1_Pa = columns["p1"];
    logged.p2_Pa = columns["p2"];
    run.initial = LoggedInitialState(logged, 0.5 * params.cylinder.stroke_m);
  } else {
    // A command alone starts from the retracted rest at the atmosphere, as
    // if logged so: a first command other than 0 is then a step at the start.
    run.initial = RetractedAtRest(params);
    logged.x_m.assign(run.t_s.size(), run.initial.position_m);
    logged.p1_Pa.assign(run.t_s.size(), run.initial.p1_Pa);
    logged.p2_Pa.assign(run.t_s.size(), run.initial.p2_Pa);
  }
  // As validation takes a log's command (one that starts at its step too).
  RigConstants rig;
  rig.supply_pressure_Pa = params.supply.supply_pressure_Pa;
  rig.atmospheric_pressure_Pa = params.supply.atmospheric_pressure_Pa;
  run.command = LoggedCommand(logged, rig);
  return run;
}

// The simulation's report, and the run written when it succeeded.
int Report(const SimulateArgs& args, const Parameters& params, const SimulationSummary& summary,
           const Trajectory& trajectory) {
  std::cout << summary.BriefReport() << "\n";
  if (summary.status == SimulationStatus::kInvalidInput) {
    throw InputError(args.params_path, 0, 0, summary.message);
  }
  if (!summary.ok()) return kNumericalFailure;  // nothing written
  std::cout << SummarizeStroke(trajectory, 0.5 * params.cylinder.stroke_m).Describe() << "\n";
  const std::string comment = "pneumaid " PNEUMAID_VERSION " simulate --params " +
                              args.params_path + "\nunit " + params.unit +
                              "; SI units, x from mid-stroke, pressures absolute";
  WriteTrajectoryCsv(trajectory, comment, args.out_path);
  std::cout << "wrote " << args.out_path << " (" << trajectory.size() << " samples)\n";
  return kSuccess;
}

// A log listed in the unit.yaml beside it (`log`) is simulated as `validate`
// simulates it (SimulateLoggedRun: the unit's rig conditions and position
// zero, the logger's pauses, a start read where the log begins unsettled,
// every channel read through its declared lag), at its own sample times up
// to --until, counted from its first sample.
int SimulateLogOfUnit(const SimulateArgs& args, const Parameters& params, const Experiment& log) {
  if (args.rate_given) {
    throw InputError("--rate", 0, 0,
                     "not for a log of a unit directory, which is simulated at its own sample "
                     "times as validate simulates it");
  }
  // A unit's log is read with its time from its first sample (ParseExperiment).
  if (!std::isnan(args.until_s) && !(args.until_s > 0)) {
    throw InputError("--until", 0, 0,
                     "expected a time after the log's first sample, from which it counts");
  }
  // The whole unit is read (its other logs show the transducer's zero and the
  // noise), so none of its files may be the output.
  const std::string directory =
      std::filesystem::weakly_canonical(args.input_path).parent_path().string();
  RefuseOverwritingInputs({args.out_path}, {directory});
  const Unit unit = ReadUnit(directory);
  NoteASetOfAnotherUnit(args.params_path, params, unit);
  const LoggedRunSimulation run = SimulateLoggedRun(params, unit, log.entry.id);
  for (const std::string& note : run.notes) std::cout << "note: " << note << "\n";
  Trajectory simulated = run.simulated;
  if (!std::isnan(args.until_s) && run.simulation.ok()) {
    const std::vector<double>& t = simulated.t_s;
    const auto end = std::upper_bound(t.begin(), t.end(), args.until_s) - t.begin();
    simulated = Slice(simulated, 0, static_cast<std::size_t>(end));
  }
  return Report(args, params, run.simulation, simulated);
}

int RunSimulate(const SimulateArgs& args) {
  RefuseOverwritingInputs({args.out_path}, {args.params_path, args.input_path});
  const Parameters params = LoadParams(args.params_path);
  if (!args.input_path.empty()) {
    if (const auto log = ReadLogOfUnit(args.input_path)) {
      return SimulateLogOfUnit(args, params, *log);
    }
  }
  CommandSignal command;
  InitialState initial = RetractedAtRest(params);
  double t0 = 0.0;
  double until = args.until_s;
  if (!args.input_path.empty()) {
    const LoggedRun run = ReadLoggedRun(args.input_path, params);
    command = run.command;
    initial = run.initial;
    t0 = run.t_s.front();
    if (std::isnan(until)) until = run.t_s.back();
  } else {
    std::vector<std::pair<double, double>> steps;
    for (const auto& text : args.steps) steps.push_back(ParseStep(text));
    command = StepCommand(steps);
    if (std::isnan(until)) throw InputError("--until", 0, 0, "required with --step");
  }
  if (!(until > t0)) throw InputError("--until", 0, 0, "expected a time after the start");
  if (!(args.rate_Hz > 0)) throw InputError("--rate", 0, 0, "expected a positive rate in Hz");
  // Eight columns of doubles: 1e7 samples are 640 MB of trajectory.
  constexpr double kMaxSamples = 1e7;
  if ((until - t0) * args.rate_Hz > kMaxSamples) {
    char message[160];
    std::snprintf(message, sizeof(message),
                  "%.3g samples asked for, expected at most %.0e (a lower --rate or --until)",
                  (until - t0) * args.rate_Hz, kMaxSamples);
    throw InputError("--rate", 0, 0, message);
  }

  Trajectory trajectory;
  const SimulationSummary summary =
      Simulate(params, command, initial, UniformTimes(t0, until, args.rate_Hz), SimulationOptions{},
               &trajectory);
  return Report(args, params, summary, trajectory);
}

}  // namespace

CommandRunner AddSimulateCommand(CLI::App* app) {
  auto args = std::make_shared<SimulateArgs>();
  app->add_option("--params", args->params_path, "parameter set (params-v1 YAML)")->required();
  auto* step = app->add_option("--step", args->steps,
                               "command step U@T0: u = U [V] from T0 [s] on (repeatable)");
  auto* input = app->add_option(
      "--input", args->input_path,
      "log whose command (t, u) drives the run; starts from its first sample's x, p1, p2 when "
      "present. A log of a unit directory is simulated as validate simulates it, at its own "
      "sample times");
  step->excludes(input);
  input->excludes(step);
  app->add_option("--until", args->until_s, "end time [s] (default: end of --input)");
  auto* rate = app->add_option("--rate", args->rate_Hz,
                               "output rate [Hz] (not for a log of a unit directory)")
                   ->capture_default_str();
  app->add_option("--out", args->out_path, "output CSV (a validation log)")
      ->required()
      ->check(InExistingDirectory);
  app->callback([step, input, rate, args]() {
    if (step->count() == 0 && input->count() == 0) {
      throw CLI::ValidationError("simulate", "one of --step or --input is required");
    }
    args->rate_given = rate->count() > 0;
  });
  return [args]() { return RunSimulate(*args); };
}

}  // namespace pneumaid::cli
