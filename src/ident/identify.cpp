#include "pneumaid/ident/identify.h"

#include <sstream>

#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/model/parameter_table.h"
#include "pneumaid/validate/logged_run.h"

namespace pneumaid {
namespace {

void ApplyBranch(const BranchFit& fit, const std::string& prefix, Parameters* params,
                 IdentifyReport* report) {
  for (const char* name : {"q_max", "a", "b", "c", "d"}) {
    const std::string path = prefix + "." + name;
    if (fit.fitted) {
      report->fitted.push_back(path);
      params->uncertainty[path] = fit.standard_errors.at(name);
    } else {
      report->priors.push_back(path + " (" + fit.note + ")");
    }
  }
  if (fit.fitted && fit.u_sat_fitted) {
    report->fitted.push_back(prefix + ".u_sat");
    params->uncertainty[prefix + ".u_sat"] = fit.standard_errors.at("u_sat");
  } else {
    report->priors.push_back(prefix + ".u_sat (" +
                             (fit.note.empty() ? std::string("fixed") : fit.note) + ")");
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
    if (!fit->fitted) continue;
    out << ", " << name << ": {final_cost: " << FormatDouble(fit->final_cost)
        << ", iterations: " << fit->iterations << ", plateaus: " << fit->plateaus << "}";
  }
  if (report.pipeline.fitted) {
    out << ", pipeline: {delta_at_rig: " << FormatDouble(report.pipeline.delta_at_rig_per_s)
        << ", tubes: " << report.pipeline.tubes.size() << "}";
  }
  if (report.friction.fitted) {
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
  if (!fit.fitted) {
    AddPriorsUnder("pipeline.", fit.note, report);
    return;
  }
  params->pipeline.delta_by_length.clear();
  for (const auto& tube : fit.tubes) {
    if (tube.fitted)
      params->pipeline.delta_by_length.push_back({tube.tube_length_m, tube.delta_per_s});
  }
  params->pipeline.delta_per_s = fit.delta_at_rig_per_s;
  params->uncertainty["pipeline.delta"] = fit.delta_at_rig_standard_error;
  report->fitted.push_back("pipeline.delta");
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
  const FrictionFitResult& fit = report->friction;
  for (const auto& [name, direction, target] :
       {std::make_tuple("positive", &fit.positive, &params->friction.positive),
        std::make_tuple("negative", &fit.negative, &params->friction.negative)}) {
    const std::string prefix = std::string("friction.") + name + ".";
    if (!fit.fitted) {
      AddPriorsUnder(prefix, fit.note, report);
      continue;
    }
    *target = direction->params;
    for (const auto& [coefficient, error] : direction->standard_errors) {
      report->fitted.push_back(prefix + coefficient);
      params->uncertainty[prefix + coefficient] = error;
    }
    for (const auto& [coefficient, why] : direction->held)
      report->priors.push_back(prefix + coefficient + " (" + why + ")");
  }
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
    params.valve.increasing = report->valve.increasing.params;
    params.valve.decreasing = report->valve.decreasing.params;
    ApplyBranch(report->valve.increasing, "valve.increasing", &params, report);
    ApplyBranch(report->valve.decreasing, "valve.decreasing", &params, report);
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
    throw InputError(unit.directory, 0, 0,
                     "the identified set is not physical: " + problems.front().path + ": " +
                         problems.front().message);
  }
  return params;
}

}  // namespace pneumaid
