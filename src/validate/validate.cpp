#include "pneumaid/validate/validate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <optional>
#include <sstream>

#include "pneumaid/io/channel_noise.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/json.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/validate/lag_start.h"
#include "pneumaid/validate/logged_run.h"

namespace pneumaid {
namespace {

// The noise of each compared channel (NoiseOf: declared, else estimated from
// the unit's logs); none where neither gives one.
std::map<std::string, double> ChannelNoises(const Unit& unit) {
  std::map<std::string, double> noise;
  for (const char* channel : {"x", "p1", "p2", "q1", "q2"}) {
    const double sigma = NoiseSigma(unit, channel);
    if (sigma > 0) noise[channel] = sigma;
  }
  return noise;
}

std::vector<std::string> MissedThresholds(const std::map<std::string, ChannelMetrics>& channels,
                                          const ValidationOptions& options) {
  std::vector<std::string> missed;
  char line[160];
  for (const auto& [channel, minimum] : options.min_fit_percent) {
    const auto found = channels.find(channel);
    if (found == channels.end()) continue;
    if (!found->second.nrmse_fit_percent) {
      // Not evaluated is not met (a run of one sample, a channel that never
      // changes: it "passed" every threshold before).
      std::snprintf(line, sizeof(line),
                    "%s fit n/a (the logged %s does not vary beyond its noise), < %.2f %%",
                    channel.c_str(), channel.c_str(), minimum);
      missed.push_back(line);
      continue;
    }
    if (*found->second.nrmse_fit_percent < minimum) {
      std::snprintf(line, sizeof(line), "%s fit %.2f %% < %.2f %%", channel.c_str(),
                    *found->second.nrmse_fit_percent, minimum);
      missed.push_back(line);
    }
  }
  for (const auto& [channel, maximum] : options.max_rmse) {
    const auto found = channels.find(channel);
    if (found == channels.end()) continue;
    if (found->second.rmse > maximum) {
      std::snprintf(line, sizeof(line), "%s RMSE %.6g > %.6g (SI)", channel.c_str(),
                    found->second.rmse, maximum);
      missed.push_back(line);
    }
  }
  return missed;
}

// A later piece's run (PieceStarts) added to the whole run's summary: its
// counters, and its failure.
void AddPiece(const SimulationSummary& piece, SimulationSummary* whole) {
  if (!piece.ok()) {
    whole->status = piece.status;
    whole->message = piece.message;
  }
  whole->steps += piece.steps;
  whole->rhs_evaluations += piece.rhs_evaluations;
  whole->jacobian_evaluations += piece.jacobian_evaluations;
  whole->error_test_failures += piece.error_test_failures;
  whole->convergence_failures += piece.convergence_failures;
  whole->restarts += piece.restarts;
  whole->events += piece.events;
  whole->simulated_time_s += piece.simulated_time_s;
  whole->wall_time_s += piece.wall_time_s;
}

void AppendPiece(const Trajectory& piece, Trajectory* whole) {
  for (std::vector<double> Trajectory::*column :
       {&Trajectory::t_s, &Trajectory::u_V, &Trajectory::x_m, &Trajectory::v_m_per_s,
        &Trajectory::p1_Pa, &Trajectory::p2_Pa, &Trajectory::q1_kg_per_s,
        &Trajectory::q2_kg_per_s}) {
    (whole->*column).insert((whole->*column).end(), (piece.*column).begin(), (piece.*column).end());
  }
}

// `experiment` simulated under `conditioned` (the unit's rig conditions, on
// its stroke) as SimulateLoggedRun says.
LoggedRunSimulation SimulateExperiment(const Parameters& conditioned, const Unit& unit,
                                       const Experiment& experiment, const PositionZero& zero,
                                       const std::map<std::string, double>& noise,
                                       const SimulationOptions& options) {
  LoggedRunSimulation out;
  out.measured = LoggedTrajectory(experiment, zero);
  const Trajectory& m = out.measured;
  // Piece by piece where the logger paused (PieceStarts), each from its own
  // logged start; the simulated pieces end to end.
  const std::vector<std::size_t> begins = PieceStarts(m);
  for (std::size_t k = 0; k < begins.size(); ++k) {
    const std::size_t end = k + 1 < begins.size() ? begins[k + 1] : m.size();
    const Trajectory piece = Slice(m, begins[k], end);
    const InitialState initial = LoggedInitialState(piece, 0.5 * conditioned.cylinder.stroke_m);
    Trajectory simulated;
    const std::optional<double> before =
        k > 0 ? std::optional<double>(m.u_V[begins[k] - 1]) : std::nullopt;
    const CommandSignal command = LoggedCommand(piece, unit.manifest.rig, before);
    const LagStart lag = ReadLagStart(conditioned, piece, command, initial, noise, options);
    if (lag.read) out.notes.push_back(lag.note);
    const SimulationSummary summary =
        Simulate(conditioned, lag.read ? lag.command : command, lag.read ? lag.initial : initial,
                 piece.t_s, options, &simulated);
    if (k == 0) {
      out.simulation = summary;
      out.simulated = std::move(simulated);
    } else {
      AddPiece(summary, &out.simulation);
      AppendPiece(simulated, &out.simulated);
    }
    if (!out.simulation.ok()) return out;
  }
  ApplyDeclaredLags(unit.manifest, &out.simulated);
  return out;
}

ExperimentValidation ValidateExperiment(const Parameters& conditioned, const Unit& unit,
                                        const Experiment& experiment, const PositionZero& zero,
                                        const ValidationOptions& options) {
  const std::map<std::string, double> noise = ChannelNoises(unit);
  LoggedRunSimulation run =
      SimulateExperiment(conditioned, unit, experiment, zero, noise, options.simulation);
  ExperimentValidation out;
  out.id = experiment.entry.id;
  out.measured = std::move(run.measured);
  out.simulated = std::move(run.simulated);
  out.simulation = run.simulation;
  out.notes = std::move(run.notes);
  if (!out.simulation.ok()) return out;
  const Trajectory& m = out.measured;
  Trajectory comparable = out.simulated;
  if (m.q1_kg_per_s.empty()) comparable.q1_kg_per_s.clear();
  if (m.q2_kg_per_s.empty()) comparable.q2_kg_per_s.clear();
  out.channels = CompareRuns(m, comparable, noise);
  out.missed = MissedThresholds(out.channels, options);
  return out;
}

// `body(conditioned, unit)`: `params` under `given_unit`'s rig conditions
// (WithRigConditions), and the unit on the set's stroke (OnTheSetsStroke).
template <typename Body>
auto UnderRigConditions(const Parameters& params, const Unit& given_unit, const Body& body) {
  const Parameters conditioned = WithRigConditions(params, given_unit);
  const std::optional<Unit> moved = OnTheSetsStroke(given_unit, params);
  return body(conditioned, moved ? *moved : given_unit);
}

// The experiment `id` of `unit`.
const Experiment& FindExperiment(const Unit& unit, const std::string& id) {
  for (const Experiment& e : unit.experiments) {
    if (e.entry.id == id) return e;
  }
  throw InputError(unit.manifest_path(), 0, 0, "no experiment '" + id + "'");
}

// `e`, which must be a run the simulator can drive.
const Experiment& Simulable(const Unit& unit, const Experiment& e) {
  if (!IsSimulable(e.entry.kind)) {
    throw InputError(unit.manifest_path(), e.entry.manifest_line, 0,
                     "experiment '" + e.entry.id + "' is a " + ToString(e.entry.kind) +
                         " log; only stroke and validation runs can be simulated");
  }
  return e;
}

}  // namespace

bool ValidationOptions::Chooses(const Experiment& e) const {
  if (experiment_ids.empty()) return e.entry.kind == ExperimentKind::kValidation;
  return std::find(experiment_ids.begin(), experiment_ids.end(), e.entry.id) !=
         experiment_ids.end();
}

bool ValidationOptions::IsValid(std::string* error) const {
  for (const auto& [channel, value] : min_fit_percent) {
    if (!(value <= 100.0) || !std::isfinite(value)) {
      if (error) {
        *error = "min_fit_percent: " + channel + ": expected a number at most 100, got " +
                 FormatDouble(value);
      }
      return false;
    }
  }
  for (const auto& [channel, value] : max_rmse) {
    if (!(value > 0) || !std::isfinite(value)) {
      if (error) {
        *error =
            "max_rmse: " + channel + ": expected a finite number > 0, got " + FormatDouble(value);
      }
      return false;
    }
  }
  return simulation.IsValid(error);
}

bool ValidationReport::numerical_failure() const {
  for (const auto& e : experiments) {
    if (!e.simulation.ok()) return true;
  }
  return false;
}

bool ValidationReport::thresholds_met() const {
  for (const auto& e : experiments) {
    if (!e.missed.empty()) return false;
  }
  return true;
}

std::string ValidationReport::BriefReport() const {
  std::ostringstream out;
  out << "Validation of unit " << unit << ": " << experiments.size() << " runs\n";
  char line[256];
  for (const auto& e : experiments) {
    if (!e.simulation.ok()) {
      out << "  " << e.id << ": SIMULATION FAILED: " << e.simulation.message << "\n";
      continue;
    }
    out << "  " << e.id << ":";
    for (const auto& [channel, metrics] : e.channels) {
      const bool pressure = channel[0] == 'p';
      const bool position = channel == "x";
      const double scale = pressure ? 1e-5 : position ? 1e3 : 1.0;
      const char* unit_name = pressure ? "bar" : position ? "mm" : "kg/s";
      char fit[32] = "n/a";  // rounded as the JSON's reader and the page round it
      if (metrics.nrmse_fit_percent)
        std::snprintf(fit, sizeof(fit), "%.2f %%", *metrics.nrmse_fit_percent);
      std::snprintf(line, sizeof(line), "  %s rmse %.4g %s, max %.4g %s, fit %s", channel.c_str(),
                    metrics.rmse * scale, unit_name, metrics.max_abs * scale, unit_name, fit);
      out << line << ";";
    }
    out << "\n";
    for (const auto& note : e.notes) out << "    note: " << note << "\n";
    for (const auto& miss : e.missed) out << "    MISSED: " << miss << "\n";
  }
  out << (numerical_failure() ? "a simulation failed\n"
          : thresholds_met()  ? "all thresholds met\n"
                              : "thresholds missed\n");
  return out.str();
}

ValidationReport ValidateUnit(const Parameters& params, const Unit& given_unit,
                              const ValidationOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw InputError("validation options", 0, 0, error);
  return UnderRigConditions(
      params, given_unit, [&](const Parameters& conditioned, const Unit& unit) {
        ValidationReport report;
        report.unit = unit.manifest.unit;
        const PositionZero zero = ReadPositionZero(unit);  // once for every run
        // Every id first, then each chosen run's kind.
        for (const auto& id : options.experiment_ids) FindExperiment(unit, id);
        for (const Experiment& e : unit.experiments) {
          if (!options.Chooses(e)) continue;
          report.experiments.push_back(
              ValidateExperiment(conditioned, unit, Simulable(unit, e), zero, options));
        }
        if (report.experiments.empty()) {
          throw InputError(unit.manifest_path(), 0, 0, "no validation experiments to validate");
        }
        return report;
      });
}

LoggedRunSimulation SimulateLoggedRun(const Parameters& params, const Unit& given_unit,
                                      const std::string& experiment_id,
                                      const SimulationOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw InputError("simulation options", 0, 0, error);
  return UnderRigConditions(
      params, given_unit, [&](const Parameters& conditioned, const Unit& unit) {
        return SimulateExperiment(conditioned, unit,
                                  Simulable(unit, FindExperiment(unit, experiment_id)),
                                  ReadPositionZero(unit), ChannelNoises(unit), options);
      });
}

}  // namespace pneumaid

namespace pneumaid {

std::string ReportToJson(const ValidationReport& report) {
  std::ostringstream out;
  out << "{\"format\": \"pneumaid-report/1\", \"unit\": " << JsonString(report.unit)
      << ", \"thresholds_met\": " << (report.thresholds_met() ? "true" : "false")
      << ", \"numerical_failure\": " << (report.numerical_failure() ? "true" : "false")
      << ",\n \"experiments\": " << ExperimentsToJson(report) << "}\n";
  return out.str();
}

std::string ExperimentsToJson(const ValidationReport& report) {
  std::ostringstream out;
  out << "[";
  for (std::size_t i = 0; i < report.experiments.size(); ++i) {
    const auto& e = report.experiments[i];
    out << (i ? ",\n  " : "\n  ") << "{\"id\": " << JsonString(e.id);
    if (!e.simulation.ok()) out << ", \"simulation_failure\": " << JsonString(e.simulation.message);
    out << ", \"channels\": {";
    std::size_t k = 0;
    for (const auto& [channel, metrics] : e.channels) {
      out << (k++ ? ", " : "") << JsonString(channel) << ": {\"rmse\": " << JsonNumber(metrics.rmse)
          << ", \"max_abs\": " << JsonNumber(metrics.max_abs) << ", \"nrmse_fit_percent\": "
          << (metrics.nrmse_fit_percent ? JsonNumber(*metrics.nrmse_fit_percent) : "null") << "}";
    }
    out << "}, \"missed\": [";
    for (std::size_t m = 0; m < e.missed.size(); ++m)
      out << (m ? ", " : "") << JsonString(e.missed[m]);
    out << "]";
    if (!e.notes.empty()) {  // how the run was started where its log did not say
      out << ", \"notes\": [";
      for (std::size_t n = 0; n < e.notes.size(); ++n)
        out << (n ? ", " : "") << JsonString(e.notes[n]);
      out << "]";
    }
    out << "}";
  }
  out << "]";
  return out.str();
}

std::string ComparisonToCsv(const ExperimentValidation& e) {
  std::ostringstream out;
  out << "# pneumaid validate: " << e.id << ", measured and simulated, SI (x from mid-stroke, "
      << "pressures absolute, mass flows)\nt,u";
  std::vector<const std::vector<double>*> columns = {&e.measured.t_s, &e.measured.u_V};
  for (const auto& [name, member] : kComparedChannels) {
    if ((e.measured.*member).empty() || (e.simulated.*member).size() != e.measured.size()) continue;
    out << "," << name << (name[0] == 'q' ? " [kg/s]" : "") << "," << name << "_sim"
        << (name[0] == 'q' ? " [kg/s]" : "");
    columns.push_back(&(e.measured.*member));
    columns.push_back(&(e.simulated.*member));
  }
  out << "\n";
  for (std::size_t row = 0; row < e.measured.size(); ++row) {
    for (std::size_t c = 0; c < columns.size(); ++c)
      out << (c ? "," : "") << FormatSignificant((*columns[c])[row], 9);
    out << "\n";
  }
  return out.str();
}

}  // namespace pneumaid
