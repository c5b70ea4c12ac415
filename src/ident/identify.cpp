#include "pneumaid/ident/identify.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <sstream>

#include "../io/provenance_map.h"
#include "held_levels.h"
#include "pneumaid/io/channel_noise.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/model/effects.h"
#include "pneumaid/model/kvp.h"
#include "pneumaid/model/parameter_table.h"
#include "pneumaid/validate/logged_run.h"

namespace pneumaid {
namespace {

// A fit's values into `params` (when it has any), its determined
// coefficients' errors into the uncertainty, and each coefficient listed as
// fitted, or as from the prior with why.
void Record(const FitResult& fit, Parameters* params, IdentifyReport* report) {
  fit.ApplyTo(params);
  const std::map<std::string, std::string> held = fit.Held();
  for (const FittedCoefficient& c : fit.coefficients) {
    const auto why = held.find(c.path);
    if (why == held.end()) {
      report->fitted.push_back(c.path);
      params->uncertainty[c.path] = c.standard_error;
    } else {
      report->priors.push_back(c.path + " (" + why->second + ")");
    }
  }
}

// Whether `paths` holds one under `prefix`.
bool Lists(const std::vector<std::string>& paths, const std::string& prefix) {
  for (const std::string& path : paths) {
    if (path.compare(0, prefix.size(), prefix) == 0) return true;
  }
  return false;
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

// The prior's effects, which the set keeps and no component fit models, each
// parameter listed as from the prior. One that acts on friction (the
// catalog's acts_on_friction) is named with what that means for friction
// fitted here: the friction fit replays the paper's law with exact stick.
void ListPriorEffects(const Parameters& params, IdentifyReport* report) {
  const bool friction_fitted = Lists(report->fitted, "friction.");
  for (const auto& [effect, values] : params.effects) {
    const EffectInfo* info = FindEffect(effect);
    for (const auto& [name, value] : values) {
      std::string why = "an effect of the prior; the component fits do not model it";
      if (info != nullptr && info->acts_on_friction && friction_fitted)
        why += ": friction.* were fitted without it, to the paper's law with exact stick";
      report->priors.push_back("effects." + effect + "." + name + " (" + why + ")");
    }
  }
}

// valve.branch is the prior's choice: no fit makes it. Where both branches
// were fitted and differ, and the stroke or validation logs close a valve
// pair part way (a held opening followed by a smaller one of the same sign,
// where a valve with hysteresis follows its decreasing branch), the choice
// matters, and the report's notes say so. (Random steps between 0.3 and 0.9 V
// simulated with `increasing` missed by 1.4 mm of x RMS where `hysteresis`
// gave 6 um.)
void NoteTheValveBranch(const Unit& unit, const Parameters& params, IdentifyReport* report) {
  const ValveFitResult& valve = report->valve;
  // (A prior of `decreasing` follows that branch whatever the command does.)
  if (params.valve.branch != ValveBranchMode::kIncreasing || !valve.increasing.has_values() ||
      !valve.decreasing.has_values()) {
    return;
  }
  int closings = 0;
  for (const Experiment& e : unit.experiments) {
    if (e.entry.kind != ExperimentKind::kStroke && e.entry.kind != ExperimentKind::kValidation)
      continue;
    const std::vector<double>& u = e.column("u");
    double held = 0;
    for (const auto& [begin, end] : internal::HeldLevels(u, kCommandNoise_V)) {
      const double level = internal::Median(std::vector<double>(
          u.begin() + static_cast<long>(begin), u.begin() + static_cast<long>(end)));
      if (std::fabs(level) > kCommandNoise_V && held * level > 0 &&
          std::fabs(level) < std::fabs(held) - kCommandNoise_V)
        ++closings;
      held = level;
    }
  }
  if (closings == 0) return;
  const auto increasing = MakeKvpCoefficients<double>(valve.increasing.params);
  const auto decreasing = MakeKvpCoefficients<double>(valve.decreasing.params);
  double largest = 0;
  for (int i = 1; i <= 100; ++i) {
    const double u = 0.01 * i;
    largest = std::max(largest, std::fabs(Kvp(u, increasing) - Kvp(u, decreasing)) /
                                    valve.increasing.params.q_max_kg_per_s);
  }
  if (largest < 0.01) return;
  char why[400];
  std::snprintf(
      why, sizeof(why),
      "the prior's increasing; the branches fitted differ by up to %.0f %% of q_max, and the "
      "stroke and validation logs close a valve pair part way %d times, where a valve "
      "with hysteresis follows its decreasing branch (branch: hysteresis) and one "
      "without its increasing one: the choice matters for these logs",
      100 * largest, closings);
  report->notes.push_back(std::string("valve.branch: ") + why);
}

// The identified set's provenance: what made it (tool, date, the unit and
// the sha256 of every log) and each component fit's cost.
std::string Provenance(const Unit& unit, const IdentifyOptions& options,
                       const IdentifyReport& report) {
  YAML::Node root(YAML::NodeType::Map);
  root["tool"] = "pneumaid " + options.tool_version;
  root["date"] = options.date;
  // Absolute: a set outlives the shell it was identified in ("." names
  // nothing once it is handed on).
  root["unit"] = unit.manifest.unit;
  std::error_code no_working_directory;  // then the directory as given
  const std::filesystem::path directory =
      std::filesystem::absolute(unit.directory, no_working_directory);
  root["unit_directory"] =
      (no_working_directory ? std::filesystem::path(unit.directory) : directory.lexically_normal())
          .string();
  if (!unit.manifest.defaults_used.empty()) {
    YAML::Node defaults(YAML::NodeType::Sequence);  // the rig constants the manifest left out
    for (const std::string& path : unit.manifest.defaults_used) defaults.push_back(path);
    root["rig_defaults_used"] = defaults;
  }
  YAML::Node inputs(YAML::NodeType::Sequence);
  for (const auto& e : unit.experiments) {
    YAML::Node input(YAML::NodeType::Map);
    input["file"] = e.entry.file;
    input["sha256"] = e.sha256;
    inputs.push_back(input);
  }
  root["inputs"] = inputs;
  for (const auto& [name, fit] : {std::make_pair("valve_increasing", &report.valve.increasing),
                                  std::make_pair("valve_decreasing", &report.valve.decreasing)}) {
    if (!fit->has_values()) continue;
    YAML::Node entry(YAML::NodeType::Map);
    entry["status"] = ToString(fit->status);
    entry["final_cost"] = FormatDouble(fit->final_cost);
    entry["iterations"] = fit->iterations;
    entry["plateaus"] = fit->plateaus;
    root[name] = entry;
  }
  if (report.pipeline.has_values()) {
    YAML::Node entry(YAML::NodeType::Map);
    entry["status"] = ToString(report.pipeline.status);
    entry["delta_at_rig"] = FormatDouble(report.pipeline.coefficients.front().value);
    entry["tubes"] = report.pipeline.tubes.size();
    root["pipeline"] = entry;
  }
  if (report.friction.has_values()) {
    YAML::Node entry(YAML::NodeType::Map);
    entry["status"] = ToString(report.friction.status);
    entry["final_cost"] = FormatDouble(report.friction.final_cost);
    entry["iterations"] = report.friction.iterations;
    entry["segments"] = report.friction.segments;
    root["friction"] = entry;
  }
  // The coefficients a fit that ran did not determine, with why (its value
  // the prior's or a reading off the logs, no `uncertainty` entry).
  YAML::Node held(YAML::NodeType::Map);
  for (const FitResult* fit :
       std::initializer_list<const FitResult*>{&report.valve, &report.pipeline, &report.friction}) {
    for (const auto& [path, why] : fit->Held()) held[path] = why;
  }
  if (held.size() > 0) root["held"] = held;
  return EmitProvenance(root);
}

// Whether `component` is fitted: requested and its kind of experiment
// logged. Otherwise its parameters (under `prefix`) stay the prior's, with
// why (in the report's priors, and as `result`'s reason, which its
// BriefReport prints); InputError when it was asked for by name and the unit
// has no such log.
bool WillFit(Component component, ExperimentKind kind, const std::string& prefix, const Unit& unit,
             const IdentifyOptions& options, IdentifyReport* report, FitResult* result) {
  const auto held_at_prior = [&](const std::string& why) {
    AddPriorsUnder(prefix, why, report);
    result->reason = why;
    return false;
  };
  if (!options.components.count(component)) return held_at_prior("not requested");
  if (HasKind(unit, kind)) return true;
  const std::string what = std::string(ToString(component));
  const std::string log = std::string(ToString(kind)) + " experiment";
  if (options.components_explicit) {
    throw InputError(
        unit.manifest_path(), 0, 0,
        "components: " + what + " was asked for, but the unit has no " + log + " to fit");
  }
  return held_at_prior("no " + log);
}

void IdentifyPipeline(const Unit& unit, const Parameters& prior, const IdentifyOptions& options,
                      Parameters* params, IdentifyReport* report) {
  if (!WillFit(Component::kPipeline, ExperimentKind::kPipeline, "pipeline.", unit, options, report,
               &report->pipeline))
    return;
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
  if (!WillFit(Component::kFriction, ExperimentKind::kStroke, "friction.", unit, options, report,
               &report->friction))
    return;
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

std::vector<std::string> IdentifyReport::NotAccepted() const {
  std::vector<std::string> out;
  using Named = std::pair<const char*, const FitResult*>;
  for (const auto& [name, fit] :
       {Named{"valve increasing", &valve.increasing}, Named{"valve decreasing", &valve.decreasing},
        Named{"pipeline", &pipeline}, Named{"friction", &friction}}) {
    if (fit->status == FitStatus::kNotConverged || fit->status == FitStatus::kNotExplained)
      out.push_back(std::string(name) + ": " + ToString(fit->status) +
                    (fit->reason.empty() ? "" : " (" + fit->reason + ")"));
  }
  return out;
}

std::string IdentifyReport::BriefReport() const {
  std::ostringstream out;
  if (!noise_note.empty()) out << noise_note << "\n";
  out << valve.BriefReport() << pipeline.BriefReport() << friction.BriefReport();
  out << "Fitted: " << fitted.size() << " parameters";
  for (const auto& path : fitted) out << "\n  " << path;
  out << "\nFrom the prior: " << priors.size() << " parameters";
  for (const auto& path : priors) out << "\n  " << path;
  out << "\n";
  for (const auto& note : notes) out << "Note: " << note << "\n";
  return out.str();
}

Parameters Identify(const Unit& unit, const Parameters& prior, const IdentifyOptions& options,
                    IdentifyReport* report) {
  std::string error;
  if (!options.IsValid(&error)) throw InputError("identify options", 0, 0, error);
  IdentifyReport unread;  // for a caller that wants the set alone
  if (report == nullptr) report = &unread;
  Parameters params = WithUnitConstants(prior, unit);
  params.uncertainty.clear();
  *report = IdentifyReport{};
  // The channels whose noise the fits read through NoiseOf (the valve fit
  // weights its levels by their own residual spread where q is undeclared).
  report->noise_note = ChannelNoiseNote(unit, {"x", "p1", "p2", "q_in", "q_out"});
  if (WillFit(Component::kValve, ExperimentKind::kValve, "valve.", unit, options, report,
              &report->valve)) {
    report->valve = FitValve(unit, prior.valve, options.valve);
    Record(report->valve, &params, report);
  }
  IdentifyPipeline(unit, prior, options, &params, report);
  IdentifyFriction(unit, prior, options, &params, report);
  ListPriorEffects(params, report);
  NoteTheValveBranch(unit, params, report);
  params.provenance_yaml = Provenance(unit, options, *report);
  const auto problems = Validate(params);
  if (!problems.empty()) {
    throw FitError("the identified set of unit " + unit.manifest.unit,
                   "not physical: " + problems.front().path + ": " + problems.front().message);
  }
  return params;
}

}  // namespace pneumaid
