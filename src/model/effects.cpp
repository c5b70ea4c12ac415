#include "pneumaid/model/effects.h"

#include <limits>

namespace pneumaid {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr ValueRange kPositive{0, false, kInf, false};
constexpr ValueRange kNonNegative{0, true, kInf, false};

std::vector<EffectInfo> MakeCatalog() {
  return {
      {"valve_lag",
       "first-order lag between command and valve opening",
       {{"tau", "s", "time constant of the valve opening", kPositive, 1e-4, 0.5, 0.01}},
       true},
      {"flow_sensor_lag",
       "first-order lag of the flow transducers (measurement only)",
       {{"tau", "s", "time constant of the flow meters", kPositive, 1e-4, 1.0, 0.05}},
       true},
      {"pipeline_lag",
       "the Eq. 5 lag, when the base model has pipeline.model: none",
       {{"delta", "1/s", "rate constant of the lag", kPositive, 0.5, 500.0, 8.0}},
       true},
      {"cross_leakage",
       "laminar leak across the piston seal, q = c (p1 - p2)",
       {{"c", "kg/(s Pa)", "leak conductance", kNonNegative, 0.0, 1e-9, 1e-11}},
       true},
      {"heat_transfer",
       "wall heat exchange of each chamber's gas",
       {{"h", "W/K", "wall heat transfer coefficient times area", kNonNegative, 0.0, 5.0, 0.05}},
       true},
      {"supply_droop",
       "supply pressure sags with the flow drawn: p_s = p_supply - r q_s(p_s)",
       {{"r", "Pa s/kg", "supply line resistance", kNonNegative, 0.0, 5e9, 3e8}},
       true},
      {"friction_pressure",
       "friction scales by 1 + kp ((p1 + p2)/2 - p_atm)",
       {{"kp", "1/Pa", "pressure sensitivity of the seal friction", kNonNegative, 0.0, 1e-5, 5e-7}},
       true,
       /*acts_on_friction=*/true},
      {"valve_deadzone",
       "no flow below |u| < u0; opening rescaled above it",
       {{"u0", "V", "dead zone of the valve opening", ValueRange{0, true, 1, false}, 0.0, 0.3,
         0.03}},
       true},
      {"stick_creep",
       "a stuck rod creeps: friction saturates within |v| < v, not at v = 0",
       {{"v", "m/s", "creep speed at which a held rod's friction reaches its Stribeck value",
         kPositive, 1e-5, 1e-3, 1e-4}},
       true,
       /*acts_on_friction=*/true},
  };
}

}  // namespace

const std::vector<EffectInfo>& EffectCatalog() {
  static const std::vector<EffectInfo> catalog = MakeCatalog();
  return catalog;
}

const EffectInfo* FindEffect(const std::string& name) {
  for (const auto& effect : EffectCatalog()) {
    if (name == effect.name) return &effect;
  }
  return nullptr;
}

bool SplitEffectPath(const std::string& path, std::string* name, std::string* parameter) {
  const std::string prefix = "effects.";
  if (path.compare(0, prefix.size(), prefix) != 0) return false;
  const auto dot = path.find('.', prefix.size());
  if (dot == std::string::npos) return false;
  *name = path.substr(prefix.size(), dot - prefix.size());
  *parameter = path.substr(dot + 1);
  return true;
}

const EffectParameterInfo* FindEffectParameter(const std::string& path) {
  std::string name, parameter;
  if (!SplitEffectPath(path, &name, &parameter)) return nullptr;
  const EffectInfo* effect = FindEffect(name);
  if (effect == nullptr) return nullptr;
  for (const EffectParameterInfo& info : effect->parameters) {
    if (parameter == info.name) return &info;
  }
  return nullptr;
}

}  // namespace pneumaid
