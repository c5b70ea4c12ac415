#include "pneumaid/ident/fit_spec.h"

#include <algorithm>
#include <iterator>

#include "../io/yaml_reader.h"
#include "pneumaid/io/files.h"
#include "pneumaid/model/effects.h"
#include "pneumaid/model/parameter_table.h"
#include "pneumaid/sim/sensitivities.h"

namespace pneumaid {
namespace {

constexpr const char* kExperimentNames = "experiment ids or kinds";

// Whether names[i] is one of the names before it (a stage lists each free
// parameter once).
bool ListedBefore(const std::vector<std::string>& names, std::size_t i) {
  return std::find(names.begin(), names.begin() + static_cast<std::ptrdiff_t>(i), names[i]) !=
         names.begin() + static_cast<std::ptrdiff_t>(i);
}

// The last stage's fit is the result (values, covariance): a parameter an
// earlier stage alone fits would move without a standard error. Why the
// spec's last stage breaks that (empty: it does not).
std::string LastStageGap(const FitSpec& spec) {
  if (spec.stages.empty() || spec.stages.back().parameters.empty()) return "";
  const std::vector<std::string>& last = spec.stages.back().parameters;
  for (const FreeParameter& p : spec.parameters) {
    if (std::find(last.begin(), last.end(), p.path) == last.end()) {
      return "stages: the last stage must fit every free parameter ('" + p.path +
             "' is not in it; list it there, or use all)";
    }
  }
  return "";
}

const char* const kChannels[] = {"x", "p1", "p2", "q1", "q2"};

// What the model accepts at a freeable path: a scalar's range or an effect
// parameter's (the catalog's); nullptr for a path that names neither.
const ValueRange* RangeOf(const std::string& path) {
  if (const ScalarParameterInfo* info = FindScalarParameter(path)) return &info->range;
  if (const EffectParameterInfo* info = FindEffectParameter(path)) return &info->range;
  return nullptr;
}

class FitSpecReader : internal::YamlReader {
 public:
  explicit FitSpecReader(std::string source) : YamlReader(std::move(source)) {}

  FitSpec Read(const std::string& text) {
    return Guarded([&] { return ReadDocument(text); });
  }

 private:
  FitSpec ReadDocument(const std::string& text) {
    const YAML::Node root = LoadMapping(
        text, std::string("expected a mapping starting with format: ") + kFitSpecFormat);
    Keys(root, "",
         {"format", "parameters", "channels", "experiments", "stages", "initial_pressures",
          "multistart", "seed", "max_iterations"});
    if (!root["format"] || Text(root["format"]) != kFitSpecFormat) {
      Fail(root, std::string("expected format: ") + kFitSpecFormat);
    }
    FitSpec spec;
    spec.source = source_;
    ReadParameters(root["parameters"], &spec);
    ReadChannels(root["channels"], &spec);
    if (const YAML::Node experiments = root["experiments"]) {
      Keys(experiments, "experiments.", {"fit", "hold_out"});
      if (experiments["fit"]) {
        spec.fit = Names(experiments["fit"], "experiments.fit", kExperimentNames, &spec.fit_lines);
      }
      if (experiments["hold_out"]) {
        spec.hold_out = Names(experiments["hold_out"], "experiments.hold_out", kExperimentNames,
                              &spec.hold_out_lines);
      }
      if (spec.fit.empty()) Fail(experiments, "experiments.fit: expected at least one experiment");
    }
    ReadStages(root["stages"], &spec);
    if (!spec.stages.empty() && spec.stages.back().friction_replay) {
      Fail(root["stages"], "stages: the last stage must fit through the simulator");
    }
    if (const std::string gap = LastStageGap(spec); !gap.empty())
      Fail(root["stages"][root["stages"].size() - 1], gap);
    if (const YAML::Node start = root["initial_pressures"]) {
      const std::string how = Text(start);
      if (how != "fit" && how != "logged") Fail(start, "initial_pressures: expected fit or logged");
      spec.fit_initial_pressures = how == "fit";
    }
    const int room =
        kMaxSensitivityParameters - (spec.fit_initial_pressures ? kInitialPressureColumns : 0);
    if (spec.parameters.size() > static_cast<size_t>(room)) {
      Fail(root["parameters"],
           "parameters: at most " + std::to_string(room) + " free (with initial_pressures: fit, " +
               std::to_string(kInitialPressureColumns) + " of the " +
               std::to_string(kMaxSensitivityParameters) + " sensitivities are the start's)");
    }
    spec.multistart = Count(root["multistart"], "multistart", 0, 1000, spec.multistart);
    spec.seed = static_cast<std::uint64_t>(Whole(root["seed"], "seed", 0, 1e15, 1));
    spec.max_iterations = Count(root["max_iterations"], "max_iterations", 1, 10000, 50);
    std::string error;
    if (!spec.IsValid(&error)) Fail(root, error);  // what the reader above does not see
    return spec;
  }

  void ReadParameters(const YAML::Node& node, FitSpec* spec) const {
    if (!node || !node.IsMap() || node.size() == 0) {
      Fail(node ? node : YAML::Node(), "parameters: expected a mapping of free parameters");
    }
    if (node.size() > static_cast<size_t>(kMaxSensitivityParameters)) {
      Fail(node, "parameters: at most " + std::to_string(kMaxSensitivityParameters) + " free");
    }
    for (const auto& entry : node) {
      FreeParameter p;
      p.path = Key(entry.first);
      p.line = entry.first.Mark().line + 1;
      const ValueRange* range = RangeOf(p.path);
      if (range == nullptr) Fail(entry.first, "unknown parameter '" + p.path + "'");
      const YAML::Node bounds = entry.second;
      const std::string where = "parameters." + p.path;
      Keys(bounds, where + ".", {"min", "max", "scale"});
      if (!bounds["min"] || !bounds["max"]) Fail(bounds, where + ": expected min and max");
      p.lower = Number(bounds["min"], where + ".min");
      p.upper = Number(bounds["max"], where + ".max");
      if (!(p.lower < p.upper)) Fail(bounds, where + ": expected min < max");
      if (!range->Contains(p.lower) || !range->Contains(p.upper)) {
        Fail(bounds, where + ": bounds must each be " + range->Describe());
      }
      if (const YAML::Node scale = bounds["scale"]) {
        const std::string name = Text(scale);
        if (name != "linear" && name != "log") Fail(scale, where + ".scale: expected linear | log");
        p.scale = name == "log" ? ParameterScale::kLog : ParameterScale::kLinear;
        if (p.scale == ParameterScale::kLog && !(p.lower > 0)) {
          Fail(bounds, where + ": a log scale needs min > 0");
        }
      }
      spec->parameters.push_back(p);
    }
  }

  void ReadChannels(const YAML::Node& node, FitSpec* spec) const {
    if (!node) {
      for (const char* c : {"x", "p1", "p2"}) spec->channels[c] = ChannelWeight{};
      return;
    }
    // A bare channel (`channels: {x, p1}`) takes the manifest's sigma and weight 1.
    Keys(node, "channels.", {kChannels[0], kChannels[1], kChannels[2], kChannels[3], kChannels[4]},
         true);
    for (const auto& entry : node) {
      const std::string name = Key(entry.first);
      ChannelWeight w;
      if (entry.second.IsMap()) {
        Keys(entry.second, "channels." + name + ".", {"sigma", "weight"});
        if (entry.second["sigma"]) {
          w.sigma = Positive(entry.second["sigma"], "channels." + name + ".sigma");
        }
        if (entry.second["weight"]) {
          w.weight = Positive(entry.second["weight"], "channels." + name + ".weight");
        }
      } else if (!entry.second.IsNull()) {
        Fail(entry.second, "channels." + name + ": expected {sigma: S, weight: W} or {}");
      }
      spec->channels[name] = w;
    }
    if (spec->channels.empty()) Fail(node, "channels: expected at least one channel");
  }

  // stages: each a list of paths, `all`, or {parameters: list | all, windows: bool}
  void ReadStages(const YAML::Node& node, FitSpec* spec) const {
    if (!node) return;
    if (!node.IsSequence() || node.size() == 0) {
      Fail(node, "stages: expected a list of stages, each a list of parameters or all");
    }
    for (const auto& item : node) {
      FitStage stage;
      // reset(), not =: assigning one yaml-cpp node to another writes through
      // to the node it refers to (here: the stage itself).
      YAML::Node parameters;
      parameters.reset(item);
      if (item.IsMap()) {
        Keys(item, "stages.", {"parameters", "windows", "friction_replay"});
        if (item["windows"]) stage.windows = Flag(item["windows"]);
        if (item["friction_replay"]) stage.friction_replay = Flag(item["friction_replay"]);
        if (stage.friction_replay) {
          if (item["parameters"] || stage.windows) {
            Fail(item, "stages: friction_replay stands alone (no parameters, no windows)");
          }
          spec->stages.push_back(stage);
          continue;
        }
        if (!item["parameters"]) {
          Fail(item, "stages: expected parameters: [paths] or parameters: all");
        }
        parameters.reset(item["parameters"]);
      }
      if (parameters.IsScalar()) {
        if (parameters.Scalar() != "all") {
          Fail(parameters, "stages: expected a list of parameters or all");
        }
        spec->stages.push_back(stage);
        continue;
      }
      stage.parameters = Names(parameters, "stages", "parameters");
      for (size_t i = 0; i < stage.parameters.size(); ++i) {
        if (spec->FindParameter(stage.parameters[i]) == nullptr) {
          Fail(parameters[i], "stages: '" + stage.parameters[i] + "' is not under parameters");
        }
        if (ListedBefore(stage.parameters, i)) {
          Fail(parameters[i], "stages: '" + stage.parameters[i] + "' listed twice in one stage");
        }
      }
      if (stage.parameters.empty()) Fail(parameters, "stages: an empty stage");
      spec->stages.push_back(stage);
    }
  }

  // A list of names (`items` says of what) and, when `lines` is given, the
  // line of each.
  std::vector<std::string> Names(const YAML::Node& node, const std::string& path,
                                 const std::string& items,
                                 std::map<std::string, int>* lines = nullptr) const {
    if (!node.IsSequence()) Fail(node, path + ": expected a list of " + items);
    std::vector<std::string> names;
    for (const auto& item : node) {
      names.push_back(Text(item));
      if (lines != nullptr) lines->emplace(names.back(), item.Mark().line + 1);
    }
    return names;
  }
};

}  // namespace

FitSpec ParseFitSpec(const std::string& text, const std::string& source) {
  return FitSpecReader(source).Read(text);
}

bool FitSpec::IsValid(std::string* error) const {
  const auto fail = [error](const std::string& what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (parameters.empty()) return fail("parameters: expected at least one free parameter");
  const int room =
      kMaxSensitivityParameters - (fit_initial_pressures ? kInitialPressureColumns : 0);
  if (parameters.size() > static_cast<std::size_t>(room)) {
    return fail("parameters: at most " + std::to_string(room) + " free");
  }
  for (std::size_t k = 0; k < parameters.size(); ++k) {
    const FreeParameter& p = parameters[k];
    const std::string where = "parameters." + p.path;
    const ValueRange* range = RangeOf(p.path);
    if (range == nullptr) return fail("parameters: unknown parameter '" + p.path + "'");
    for (std::size_t j = 0; j < k; ++j) {
      if (parameters[j].path == p.path) return fail(where + ": freed twice");
    }
    if (!(p.lower < p.upper)) return fail(where + ": expected min < max");
    if (!range->Contains(p.lower) || !range->Contains(p.upper)) {
      return fail(where + ": bounds must each be " + range->Describe());
    }
    if (p.scale == ParameterScale::kLog && !(p.lower > 0)) {
      return fail(where + ": a log scale needs min > 0");
    }
  }
  if (channels.empty()) return fail("channels: expected at least one channel");
  for (const auto& [name, w] : channels) {
    if (std::find(std::begin(kChannels), std::end(kChannels), name) == std::end(kChannels)) {
      return fail("channels: unknown channel '" + name + "' (expected x, p1, p2, q1 or q2)");
    }
    if (!(w.sigma >= 0) || !(w.weight > 0)) {
      return fail("channels." + name + ": expected sigma >= 0 and weight > 0");
    }
  }
  if (fit.empty()) return fail("experiments.fit: expected at least one experiment");
  for (const FitStage& stage : stages) {
    if (stage.friction_replay && (stage.windows || !stage.parameters.empty())) {
      return fail("stages: friction_replay stands alone (no parameters, no windows)");
    }
    for (std::size_t k = 0; k < stage.parameters.size(); ++k) {
      const std::string& path = stage.parameters[k];
      if (FindParameter(path) == nullptr) {
        return fail("stages: '" + path + "' is not under parameters");
      }
      if (ListedBefore(stage.parameters, k)) {
        return fail("stages: '" + path + "' listed twice in one stage");
      }
    }
  }
  if (!stages.empty() && stages.back().friction_replay) {
    return fail("stages: the last stage must fit through the simulator");
  }
  if (const std::string gap = LastStageGap(*this); !gap.empty()) return fail(gap);
  if (multistart < 0 || multistart > 1000) return fail("multistart: expected 0 to 1000");
  if (max_iterations < 1) return fail("max_iterations: expected >= 1");
  return true;
}

const FreeParameter* FitSpec::FindParameter(const std::string& path) const {
  for (const FreeParameter& p : parameters) {
    if (p.path == path) return &p;
  }
  return nullptr;
}

FitSpec LoadFitSpec(const std::string& path) {
  return ParseFitSpec(ReadTextFile(path, "fit spec"), path);
}

}  // namespace pneumaid
