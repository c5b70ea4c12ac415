// Validation: simulate a parameter set on a unit's validation logs (their
// measured command and first sample) and measure, per channel, how far the
// simulation is from the measurement.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "pneumaid/eval/metrics.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/model/parameters.h"
#include "pneumaid/sim/simulate.h"
#include "pneumaid/validate/logged_run.h"

namespace pneumaid {

struct ValidationOptions {
  // How each run is simulated.
  SimulationOptions simulation;
  // Quality thresholds; a run that misses one fails validation (exit 4).
  // Channel -> lowest acceptable NRMSE fit [%].
  std::map<std::string, double> min_fit_percent = {{"x", 95.0}};
  // Channel -> highest acceptable RMSE [SI units: Pa for pressures].
  std::map<std::string, double> max_rmse = {{"p1", 1.0e4}, {"p2", 1.0e4}};
  // Experiment ids to validate; empty: every experiment of kind validation.
  std::vector<std::string> experiment_ids;

  bool IsValid(std::string* error) const;
  // Whether `e` is one of the runs to validate (experiment_ids, or every
  // validation run when it is empty).
  bool Chooses(const Experiment& e) const;
};

struct ExperimentValidation {
  std::string id;
  Trajectory measured;
  Trajectory simulated;  // flows as the declared meters would read them
  std::map<std::string, ChannelMetrics> channels;
  SimulationSummary simulation;
  std::vector<std::string> missed;  // thresholds missed, as sentences
  std::vector<std::string>
      notes;  // how the run was started where the log did not say (lag_start.h)
};

struct ValidationReport {
  std::string unit;
  std::vector<ExperimentValidation> experiments;

  bool numerical_failure() const;  // a simulation failed
  bool thresholds_met() const;
  std::string BriefReport() const;  // a table of the metrics in display units
};

// Throws InputError for an unknown experiment id (every id checked first), a
// chosen experiment the simulator cannot run (a valve or tube test) or a unit
// without validation runs; numerical failures are reported in the result.
ValidationReport ValidateUnit(const Parameters& params, const Unit& unit,
                              const ValidationOptions& options);

// One logged run of a unit simulated as validation simulates it.
struct LoggedRunSimulation {
  Trajectory measured;   // the log, x less the transducer's zero (ReadPositionZero)
  Trajectory simulated;  // at the log's sample times, read through the declared lags
  SimulationSummary simulation;
  std::vector<std::string> notes;  // how a run was started where the log did not say
};

// The run `experiment_id` (a stroke or validation log) of `unit` under
// `params`: with the unit's rig conditions (WithRigConditions) on its stroke
// (OnTheSetsStroke), piece by piece where the logger paused (PieceStarts),
// each from its logged first sample and command (LoggedInitialState,
// LoggedCommand), or from a start read off the log where it begins unsettled
// (ReadLagStart), every channel read through its declared lag
// (ApplyDeclaredLags). The
// one home of how a logged run is simulated: ValidateUnit compares what it
// gives. Throws InputError for bad options or an experiment it cannot run;
// a numerical failure is in `simulation`.
LoggedRunSimulation SimulateLoggedRun(const Parameters& params, const Unit& unit,
                                      const std::string& experiment_id,
                                      const SimulationOptions& options = {});

}  // namespace pneumaid

namespace pneumaid {

// The machine-readable report (`pneumaid-report/1`, docs/params-format.md):
// per experiment and channel rmse, max_abs, nrmse_fit_percent (null where
// undefined), SI units.
std::string ReportToJson(const ValidationReport& report);

// The "experiments" array of that report, for reports that embed it (diagnose).
std::string ExperimentsToJson(const ValidationReport& report);

// Measured and simulated channels side by side, SI, one row per sample:
// t,u,x,x_sim,p1,p1_sim,... (what a plot or a spreadsheet needs).
std::string ComparisonToCsv(const ExperimentValidation& experiment);

}  // namespace pneumaid
