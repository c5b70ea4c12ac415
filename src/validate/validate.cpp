#include "pneumaid/validate/validate.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <sstream>

#include "pneumaid/io/input_error.h"

namespace pneumaid {
namespace {

constexpr double kGeometryTolerance = 0.01;

std::string ManifestPath(const Unit& unit) { return unit.directory + "/unit.yaml"; }

bool Stated(const Manifest& manifest, const std::string& path) {
  for (const auto& used : manifest.defaults_used) {
    if (used == path) return false;
  }
  return true;
}

void CheckGeometry(const Unit& unit, const std::string& what, double from_manifest,
                   double from_params, bool stated) {
  if (!stated || std::fabs(from_manifest / from_params - 1.0) <= kGeometryTolerance) return;
  char message[256];
  std::snprintf(message, sizeof(message),
                "geometry disagrees with the parameter set by more than 1 %%: %s is %.6g here, "
                "%.6g in the parameter set",
                what.c_str(), from_manifest, from_params);
  throw InputError(ManifestPath(unit), 0, 0, message);
}

// The simulated run as the rig's instruments would have logged it: flows
// through the declared meter lags.
void ApplyDeclaredLags(const Manifest& manifest, Trajectory* run) {
  for (const auto& [name, values] :
       {std::make_pair("q1", &run->q1_kg_per_s), std::make_pair("q2", &run->q2_kg_per_s)}) {
    const double tau_s = manifest.DeclaredTau(name, 0.0);
    if (tau_s > 0) *values = FirstOrderLag(run->t_s, *values, tau_s);
  }
}

std::map<std::string, double> DeclaredNoise(const Manifest& manifest) {
  std::map<std::string, double> noise;
  for (const auto& [name, sensor] : manifest.sensors) {
    if (sensor.sigma) noise[name] = *sensor.sigma;
  }
  return noise;
}

std::vector<std::string> MissedThresholds(const std::map<std::string, ChannelMetrics>& channels,
                                          const ValidationOptions& options) {
  std::vector<std::string> missed;
  char line[160];
  for (const auto& [channel, minimum] : options.min_fit_percent) {
    const auto found = channels.find(channel);
    if (found == channels.end() || !found->second.nrmse_fit_percent) continue;
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

ExperimentValidation ValidateExperiment(const Parameters& params, const Unit& unit,
                                        const Experiment& experiment,
                                        const ValidationOptions& options) {
  ExperimentValidation out;
  out.id = experiment.entry.id;
  out.measured = experiment.AsTrajectory();
  const Trajectory& m = out.measured;
  const InitialState initial = LoggedInitialState(m, 0.5 * params.cylinder.stroke_m);
  out.simulation = Simulate(params, SampledCommand(m.t_s, m.u_V), initial, m.t_s,
                            options.simulation, &out.simulated);
  if (!out.simulation.ok()) return out;
  ApplyDeclaredLags(unit.manifest, &out.simulated);
  Trajectory comparable = out.simulated;
  if (m.q1_kg_per_s.empty()) comparable.q1_kg_per_s.clear();
  if (m.q2_kg_per_s.empty()) comparable.q2_kg_per_s.clear();
  out.channels = CompareRuns(m, comparable, DeclaredNoise(unit.manifest));
  out.missed = MissedThresholds(out.channels, options);
  return out;
}

}  // namespace

bool ValidationOptions::IsValid(std::string* error) const {
  for (const auto& [channel, value] : min_fit_percent) {
    if (!(value <= 100.0) || !std::isfinite(value)) {
      if (error) *error = "min_fit_percent for " + channel + " must be at most 100";
      return false;
    }
  }
  for (const auto& [channel, value] : max_rmse) {
    if (!(value > 0)) {
      if (error) *error = "max_rmse for " + channel + " must be > 0";
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
      std::snprintf(line, sizeof(line), "  %s rmse %.4g %s, max %.4g %s, fit %s", channel.c_str(),
                    metrics.rmse * scale, unit_name, metrics.max_abs * scale, unit_name,
                    metrics.nrmse_fit_percent
                        ? (std::to_string(*metrics.nrmse_fit_percent).substr(0, 5) + " %").c_str()
                        : "n/a");
      out << line << ";";
    }
    out << "\n";
    for (const auto& miss : e.missed) out << "    MISSED: " << miss << "\n";
  }
  out << (numerical_failure() ? "a simulation failed\n"
          : thresholds_met()  ? "all thresholds met\n"
                              : "thresholds missed\n");
  return out.str();
}

// The state a run starts from: the mean of its leading samples while the
// command has not yet changed (at most 50), so that one noisy first sample
// does not set the start. A log that starts moving gets its first sample.
InitialState LoggedInitialState(const Trajectory& m, double half_stroke_m, int* samples_averaged) {
  std::size_t n = 1;
  while (n < m.size() && n < 50 && m.u_V[n] == m.u_V[0]) ++n;
  const auto mean = [n](const std::vector<double>& v) {
    return std::accumulate(v.begin(), v.begin() + static_cast<long>(n), 0.0) /
           static_cast<double>(n);
  };
  InitialState initial;
  initial.position_m = mean(m.x_m);
  initial.p1_Pa = mean(m.p1_Pa);
  initial.p2_Pa = mean(m.p2_Pa);
  const double moved = std::fabs(m.x_m[n - 1] - m.x_m[0]);
  if (moved > 1e-4) {  // not at rest: averaging would blur a moving start
    initial.position_m = m.x_m.front();
    initial.p1_Pa = m.p1_Pa.front();
    initial.p2_Pa = m.p2_Pa.front();
    n = 1;
  }
  if (samples_averaged != nullptr) *samples_averaged = static_cast<int>(n);
  // A rod resting on an end stop reads up to a few noise sigmas beyond it.
  initial.position_m = std::clamp(initial.position_m, -half_stroke_m, half_stroke_m);
  return initial;
}

Parameters WithRigConditions(const Parameters& params, const Unit& unit) {
  const Manifest& m = unit.manifest;
  const RigConstants& rig = m.rig;
  CheckGeometry(unit, "area_1 from rig.cylinder.bore", rig.area_1_m2(), params.cylinder.area_1_m2,
                Stated(m, "rig.cylinder.bore"));
  CheckGeometry(unit, "area_2 from rig.cylinder.bore and rod", rig.area_2_m2(),
                params.cylinder.area_2_m2,
                Stated(m, "rig.cylinder.bore") || Stated(m, "rig.cylinder.rod"));
  CheckGeometry(unit, "rig.cylinder.stroke", rig.stroke_m, params.cylinder.stroke_m,
                Stated(m, "rig.cylinder.stroke"));
  CheckGeometry(unit, "rig.cylinder.dead_volume_1", rig.dead_volume_1_m3,
                params.cylinder.dead_volume_1_m3, Stated(m, "rig.cylinder.dead_volume_1"));
  CheckGeometry(unit, "rig.cylinder.dead_volume_2", rig.dead_volume_2_m3,
                params.cylinder.dead_volume_2_m3, Stated(m, "rig.cylinder.dead_volume_2"));
  Parameters out = params;
  ApplyRigConditions(rig, &out);
  return out;
}

ValidationReport ValidateUnit(const Parameters& params, const Unit& unit,
                              const ValidationOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw InputError("validation options", 0, 0, error);
  const Parameters conditioned = WithRigConditions(params, unit);
  ValidationReport report;
  report.unit = unit.manifest.unit;
  for (const auto& id : options.experiment_ids) {
    bool found = false;
    for (const auto& e : unit.experiments) found = found || e.entry.id == id;
    if (!found) throw InputError(ManifestPath(unit), 0, 0, "no experiment '" + id + "'");
  }
  for (const Experiment& e : unit.experiments) {
    const bool chosen =
        options.experiment_ids.empty()
            ? e.entry.kind == ExperimentKind::kValidation
            : std::count(options.experiment_ids.begin(), options.experiment_ids.end(), e.entry.id);
    if (!chosen) continue;
    if (e.entry.kind != ExperimentKind::kValidation && e.entry.kind != ExperimentKind::kStroke) {
      throw InputError(ManifestPath(unit), e.entry.manifest_line, 0,
                       "experiment '" + e.entry.id + "' is a " + ToString(e.entry.kind) +
                           " log; only stroke and validation runs can be simulated");
    }
    report.experiments.push_back(ValidateExperiment(conditioned, unit, e, options));
  }
  if (report.experiments.empty()) {
    throw InputError(ManifestPath(unit), 0, 0, "no validation experiments to validate");
  }
  return report;
}

}  // namespace pneumaid

namespace pneumaid {
namespace {

std::string JsonNumber(double value) {
  if (!std::isfinite(value)) return "null";
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), "%.9g", value);
  return buffer;
}

std::string JsonString(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof(escaped), "\\u%04x", c);
      out += escaped;
      continue;
    }
    out += c;
  }
  return out + "\"";
}

}  // namespace

std::string ReportToJson(const ValidationReport& report) {
  std::ostringstream out;
  out << "{\"format\": \"pneumaid-report/1\", \"unit\": " << JsonString(report.unit)
      << ", \"thresholds_met\": " << (report.thresholds_met() ? "true" : "false")
      << ", \"numerical_failure\": " << (report.numerical_failure() ? "true" : "false")
      << ",\n \"experiments\": [";
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
    out << "]}";
  }
  out << "]}\n";
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
  char value[32];
  for (std::size_t row = 0; row < e.measured.size(); ++row) {
    for (std::size_t c = 0; c < columns.size(); ++c) {
      std::snprintf(value, sizeof(value), "%.9g", (*columns[c])[row]);
      out << (c ? "," : "") << value;
    }
    out << "\n";
  }
  return out.str();
}

}  // namespace pneumaid
