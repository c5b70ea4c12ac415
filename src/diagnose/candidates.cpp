#include "candidates.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "pneumaid/ident/friction_fit.h"
#include "pneumaid/model/effects.h"
#include "pneumaid/model/parameter_table.h"

namespace pneumaid::diagnose_internal {

std::vector<std::string> SignatureChannels(const std::string& effect) {
  // A measurement effect can only change what its instrument reads; an effect
  // in the plant reaches every channel (pressure drives the rod, the rod the
  // volumes, the pressures the flows), so its channels are all of them and
  // its regimes (docs/effects.md) are the evidence, not a veto.
  if (effect == "flow_sensor_lag") return {"q1", "q2"};
  return {"x", "p1", "p2", "q1", "q2"};
}

std::vector<FreeParameter> BaseParameters(const Parameters& params, bool static_friction) {
  std::vector<FreeParameter> base;
  const auto around = [&params](const std::string& path, double low, double high,
                                ParameterScale scale) {
    double value = 0;
    GetParameter(params, path, &value);
    return FreeParameter{path, value * low, value * high, scale};
  };
  base.push_back(around("valve.increasing.q_max", 0.5, 2.0, ParameterScale::kLog));
  if (params.pipeline.model != PipelineModel::kNone) {
    base.push_back(around("pipeline.delta", 0.25, 4.0, ParameterScale::kLog));
  } else if (params.effects.count("pipeline_lag")) {
    base.push_back(around("effects.pipeline_lag.delta", 0.25, 4.0, ParameterScale::kLog));
  }
  std::vector<std::string> friction = {"friction.positive.Fd", "friction.negative.Fd"};
  if (static_friction)
    friction.insert(friction.end(), {"friction.positive.Fs", "friction.negative.Fs"});
  for (const std::string& path : friction) {
    double value = 0;
    GetParameter(params, path, &value);
    base.push_back({path, 0.0, 3.0 * value + 2.0, ParameterScale::kLinear});
  }
  return base;
}

Parameters WithEffect(const Parameters& params, const std::string& effect, double fraction) {
  Parameters out = params;
  const EffectInfo* info = FindEffect(effect);
  auto& values = out.effects[effect];
  for (const EffectParameterInfo& p : info->parameters) {
    values[p.name] = std::max(fraction * p.typical, p.plausible_min);
  }
  return out;
}

std::vector<Parameters> DataStarts(const Parameters& reference, const std::string& effect,
                                   const Unit& unit, const std::vector<std::string>& runs,
                                   bool static_friction) {
  // Only the friction's own effect gains from it: every other candidate
  // starts where the base model's fit (which had it) stopped.
  if (!effect.empty() && effect != "friction_pressure") return {};
  SlideFrictionOptions slides;
  slides.pressure_gain = effect == "friction_pressure";
  slides.static_friction = static_friction;
  // The base model's fit holds a kp the set already has (a named effect).
  double kp = 0;
  if (GetParameter(reference, "effects.friction_pressure.kp", &kp)) slides.kp_per_Pa = kp;
  const SlideFrictionStart read =
      FrictionFromSlides(unit, runs, reference.friction, FrictionFitOptions{}, slides);
  if (!read.ok) return {};
  Parameters start = effect.empty() ? reference : WithEffect(reference, effect);
  start.friction = read.friction;
  if (slides.pressure_gain) {
    const EffectParameterInfo& kp = FindEffect(effect)->parameters.front();
    start.effects[effect][kp.name] =
        std::clamp(read.kp_per_Pa, std::max(kp.plausible_min, 0.01 * kp.typical), kp.plausible_max);
  }
  return {start};
}

std::vector<FreeParameter> CandidateParameters(const Parameters& with_effect,
                                               const std::string& effect, bool static_friction) {
  std::vector<FreeParameter> free;
  for (const EffectParameterInfo& p : FindEffect(effect)->parameters) {
    const bool log = p.plausible_min > 0;
    free.push_back({"effects." + effect + "." + p.name, p.plausible_min, p.plausible_max,
                    log ? ParameterScale::kLog : ParameterScale::kLinear});
  }
  for (const FreeParameter& b : BaseParameters(with_effect, static_friction)) {
    const bool taken = std::any_of(free.begin(), free.end(),
                                   [&b](const FreeParameter& f) { return f.path == b.path; });
    if (!taken) free.push_back(b);  // pipeline_lag's delta is the effect's own
  }
  return free;
}

FitSpec MakeSpec(const std::vector<FreeParameter>& parameters, const std::vector<std::string>& fit,
                 const std::map<std::string, double>& scale, const DiagnoseOptions& options,
                 const std::string& name) {
  FitSpec spec;
  spec.parameters = parameters;
  for (const auto& [channel, variance] : scale) spec.channels[channel] = {std::sqrt(variance), 1.0};
  spec.fit = fit;
  spec.hold_out.clear();
  spec.fit_initial_pressures = false;
  spec.max_iterations = options.max_iterations;
  spec.source = "diagnose: " + name;
  return spec;
}

std::vector<std::vector<std::string>> Folds(const std::vector<std::string>& runs) {
  const std::size_t k = std::min<std::size_t>(runs.size(), 3);
  std::vector<std::vector<std::string>> folds(k);
  for (std::size_t i = 0; i < runs.size(); ++i) folds[i % k].push_back(runs[i]);
  return folds;
}

std::vector<std::string> MovedBase(const Parameters& reference, const Parameters& candidate,
                                   const std::vector<FreeParameter>& base) {
  std::vector<std::string> moved;
  for (const FreeParameter& p : base) {
    double a = 0, b = 0;
    GetParameter(reference, p.path, &a);
    GetParameter(candidate, p.path, &b);
    // The identification tolerances (issue 12): forces 5 % or 0.1 N, the
    // valve gain 1 %, the tube lag 5 %.
    const bool force = p.path.rfind("friction.", 0) == 0;
    const double fraction = force ? 0.05 : p.path.find("q_max") != std::string::npos ? 0.01 : 0.05;
    const double tolerance = std::max(fraction * std::fabs(a), force ? 0.1 : 0.0);
    if (std::fabs(b - a) > tolerance) {
      char line[200];
      std::snprintf(line, sizeof(line), "%s %.4g -> %.4g", p.path.c_str(), a, b);
      moved.push_back(line);
    }
  }
  return moved;
}

}  // namespace pneumaid::diagnose_internal

namespace pneumaid {

std::vector<std::string> AbsentEffects(const Parameters& params) {
  std::vector<std::string> absent;
  for (const EffectInfo& effect : EffectCatalog()) {
    if (params.effects.count(effect.name)) continue;
    const std::string name = effect.name;
    if (name == "pipeline_lag" && params.pipeline.model != PipelineModel::kNone) continue;
    absent.push_back(name);
  }
  return absent;
}

std::vector<std::string> PresentEffects(const std::vector<std::string>& effects,
                                        const Parameters& params) {
  const std::vector<std::string> absent = AbsentEffects(params);
  std::vector<std::string> present;
  for (const std::string& effect : effects) {
    if (std::find(absent.begin(), absent.end(), effect) == absent.end()) present.push_back(effect);
  }
  return present;
}

bool EffectsAbsent(const std::vector<std::string>& effects, const Parameters& params,
                   const std::string& set_name, std::string* error) {
  const std::vector<std::string> present = PresentEffects(effects, params);
  if (present.empty()) return true;
  if (error != nullptr) {
    const std::string& effect = present.front();
    *error = "effects: '" + effect + "' is already in the " + set_name +
             (effect == "pipeline_lag" ? " (or its base model has a tube lag)" : "");
  }
  return false;
}

}  // namespace pneumaid
