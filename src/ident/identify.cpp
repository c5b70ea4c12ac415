#include "pneumaid/ident/identify.h"

#include <sstream>

#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/model/parameter_table.h"
#include "pneumaid/validate/logged_run.h"

namespace pneumaid {
namespace {

// A fit's values into `params` (when it has any), its determined
// coefficients' errors into the uncertainty, and each coefficient listed as
// fitted, or as from the prior with why.
void Record(const FitResult& fit, Parameters* params, IdentifyReport* report) {
  fit.ApplyTo(params);
  for (const FittedCoefficient& c : fit.coefficients) {
    if (fit.has_values() && c.determined()) {
      report->fitted.push_back(c.path);
      params->uncertainty[c.path] = c.standard_error;
    } else {
      report->priors.push_back(c.path + " (" + (c.held.empty() ? fit.reason : c.held) + ")");
    }
  }
}

bool HasKind(const Unit& unit, ExperimentKind kind) {
  for (const auto& e : unit.experiments) {
    if (e.entry.kind == kind) return true;
  }
  return false;
}

void AddPriorsUnder(const std::string& prefix, const std::string& why, IdentifyReport* report) {
  for (const auto& info : ScalarParameterTable()) {
    const std::string path = info.path;
    if (path.compare(0, prefix.size(), prefix) == 0)
      report->priors.push_back(path + " (" + why + ")");
  }
}

std::string QuoteYaml(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

std::string Provenance(const Unit& unit, const IdentifyOptions& options,
                       const IdentifyReport& report) {
  std::ostringstream out;
  out << "{tool: " << QuoteYaml("pneumaid " + options.tool_version)
      << ", date: " << QuoteYaml(options.date) << ", unit_directory: " << QuoteYaml(unit.directory)
      << ", inputs: [";
  for (std::size_t i = 0; i < unit.experiments.size(); ++i) {
    const auto& e = unit.experiments[i];
    out << (i ? ", " : "") << "{file: " << QuoteYaml(e.entry.file) << ", sha256: " << e.sha256
        << "}";
  }
  out << "]";
  for (const auto& [name, fit] : {std::make_pair("valve_increasing", &report.valve.increasing),
                                  std::make_pair("valve_decreasing", &report.valve.decreasing)}) {
    if (!fit->has_values()) continue;
    out << ", " << name << ": {final_cost: " << FormatDouble(fit->final_cost)
        << ", iterations: " << fit->iterations << ", plateaus: " << fit->plateaus << "}";
  }
  if (report.pipeline.has_values()) {
    out << ", pipeline: {delta_at_rig: " << FormatDouble(report.pipeline.coefficients.front().value)
        << ", tubes: " << report.pipeline.tubes.size() << "}";
  }
  if (report.friction.has_values()) {
    out << ", friction: {final_cost: " << FormatDouble(report.friction.final_cost)
        << ", iterations: " << report.friction.iterations
        << ", segments: " << report.friction.segments << "}";
  }
  out << "}";
  return out.str();
}

void IdentifyPipeline(const Unit& unit, const Parameters& prior, const IdentifyOptions& options,
                      Parameters* params, IdentifyReport* report) {
  if (!options.components.count(Component::kPipeline)) {
    AddPriorsUnder("pipeline.", "not requested", report);
    return;
  }
  if (!HasKind(unit, ExperimentKind::kPipeline)) {
    if (options.components_explicit) {
      throw InputError(
          unit.manifest_path(), 0, 0,
          "components: pipeline was asked for, but the unit has no pipeline experiment to fit");
    }
    AddPriorsUnder("pipeline.", "no pipeline experiment", report);
    return;
  }
  PipelineFitOptions pipeline_options = options.pipeline;
  pipeline_options.initial_delta_per_s = prior.pipeline.delta_per_s;
  report->pipeline = FitPipeline(unit, pipeline_options);
  const PipelineFitResult& fit = report->pipeline;
  Record(fit, params, report);
  if (!fit.has_values()) return;
  params->pipeline.delta_by_length.clear();
  for (const auto& tube : fit.tubes) {
    if (tube.has_values())
      params->pipeline.delta_by_length.push_back({tube.tube_length_m, tube.delta_per_s()});
  }
  report->fitted.push_back("pipeline.delta_by_length");
}

void IdentifyFriction(const Unit& unit, const Parameters& prior, const IdentifyOptions& options,
                      Parameters* params, IdentifyReport* report) {
  if (!options.components.count(Component::kFriction)) {
    AddPriorsUnder("friction.", "not requested", report);
    return;
  }
  if (!HasKind(unit, ExperimentKind::kStroke)) {
    if (options.components_explicit) {
      throw InputError(
          unit.manifest_path(), 0, 0,
          "components: friction was asked for, but the unit has no stroke experiment to fit");
    }
    AddPriorsUnder("friction.", "no stroke experiment", report);
    return;
  }
  report->friction = FitFriction(unit, prior.friction, options.friction);
  Record(report->friction, params, report);
}

}  // namespace

const char* ToString(Component component) {
  switch (component) {
    case Component::kValve:
      return "valve";
    case Component::kPipeline:
      return "pipeline";
    case Component::kFriction:
      return "friction";
  }
  return "?";
}

bool IdentifyOptions::IsValid(std::string* error) const {
  return valve.IsValid(error) && pipeline.IsValid(error) && friction.IsValid(error);
}

std::string IdentifyReport::BriefReport() const {
  std::ostringstream out;
  out << valve.BriefReport() << pipeline.BriefReport() << friction.BriefReport();
  out << "Fitted: " << fitted.size() << " parameters";
  for (const auto& path : fitted) out << "\n  " << path;
  out << "\nFrom the prior: " << priors.size() << " parameters";
  for (const auto& path : priors) out << "\n  " << path;
  out << "\n";
  return out.str();
}

Parameters Identify(const Unit& unit, const Parameters& prior, const IdentifyOptions& options,
                    IdentifyReport* report) {
  std::string error;
  if (!options.IsValid(&error)) throw InputError("identify options", 0, 0, error);
  Parameters params = WithUnitConstants(prior, unit);
  params.uncertainty.clear();
  *report = IdentifyReport{};
  const bool valve_wanted = options.components.count(Component::kValve) > 0;
  if (valve_wanted && HasKind(unit, ExperimentKind::kValve)) {
    report->valve = FitValve(unit, prior.valve, options.valve);
    Record(report->valve, &params, report);
  } else if (valve_wanted && options.components_explicit) {
    throw InputError(
        unit.manifest_path(), 0, 0,
        "components: valve was asked for, but the unit has no valve experiment to fit");
  } else {
    AddPriorsUnder("valve.", "no valve experiment", report);
  }
  IdentifyPipeline(unit, prior, options, &params, report);
  IdentifyFriction(unit, prior, options, &params, report);
  params.provenance_yaml = Provenance(unit, options, *report);
  const auto problems = Validate(params);
  if (!problems.empty()) {
    throw FitError("the identified set of unit " + unit.manifest.unit,
                   "not physical: " + problems.front().path + ": " + problems.front().message);
  }
  return params;
}

}  // namespace pneumaid
