#include "pneumaid/model/parameter_table.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "pneumaid/model/effects.h"

namespace pneumaid {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr ValueRange kPositive{0, false, kInf, false};
constexpr ValueRange kNonNegative{0, true, kInf, false};
constexpr ValueRange kAnyFinite{-kInf, false, kInf, false};
constexpr ValueRange kRatioAboveOne{1, false, 3, true};
constexpr ValueRange kSaturationOpening{0, false, 1, true};

// Expands to the two accessors of one table row.
#define PNEUMAID_REF(member)                         \
  [](Parameters& p) -> double& { return p.member; }, \
      [](const Parameters& p) -> double { return p.member; }

std::vector<ScalarParameterInfo> MakeTable() {
  return {
      {"gas.k", "-", "heat capacity ratio of the gas", kRatioAboveOne,
       PNEUMAID_REF(gas.heat_capacity_ratio)},
      {"gas.R", "J/(kg K)", "specific gas constant", kPositive,
       PNEUMAID_REF(gas.gas_constant_J_per_kgK)},
      {"gas.T", "K", "gas temperature (supply and chambers)", kPositive,
       PNEUMAID_REF(gas.temperature_K)},
      {"supply.supply_pressure", "Pa", "absolute supply pressure", kPositive,
       PNEUMAID_REF(supply.supply_pressure_Pa)},
      {"supply.atmospheric_pressure", "Pa", "absolute atmospheric (exhaust) pressure", kPositive,
       PNEUMAID_REF(supply.atmospheric_pressure_Pa)},
      {"cylinder.area_1", "m2", "cap-side piston area (chamber 1)", kPositive,
       PNEUMAID_REF(cylinder.area_1_m2)},
      {"cylinder.area_2", "m2", "rod-side annulus area (chamber 2)", kPositive,
       PNEUMAID_REF(cylinder.area_2_m2)},
      {"cylinder.stroke", "m", "stroke length L", kPositive, PNEUMAID_REF(cylinder.stroke_m)},
      {"cylinder.dead_volume_1", "m3", "chamber 1 volume at the retracted end", kPositive,
       PNEUMAID_REF(cylinder.dead_volume_1_m3)},
      {"cylinder.dead_volume_2", "m3", "chamber 2 volume at the extended end", kPositive,
       PNEUMAID_REF(cylinder.dead_volume_2_m3)},
      {"cylinder.load_mass", "kg", "moving mass: load, piston and rod", kPositive,
       PNEUMAID_REF(cylinder.load_mass_kg)},
      {"valve.normalization", "-", "N of Eq. 4, kept as given", kPositive,
       PNEUMAID_REF(valve.normalization)},
      {"valve.increasing.a", "-", "u^4 coefficient, increasing branch", kAnyFinite,
       PNEUMAID_REF(valve.increasing.a)},
      {"valve.increasing.b", "-", "u^3 coefficient, increasing branch", kAnyFinite,
       PNEUMAID_REF(valve.increasing.b)},
      {"valve.increasing.c", "-", "u^2 coefficient, increasing branch", kAnyFinite,
       PNEUMAID_REF(valve.increasing.c)},
      {"valve.increasing.d", "-", "u coefficient, increasing branch", kAnyFinite,
       PNEUMAID_REF(valve.increasing.d)},
      {"valve.increasing.q_max", "kg/s", "K_vp at saturation, increasing branch", kPositive,
       PNEUMAID_REF(valve.increasing.q_max_kg_per_s)},
      {"valve.increasing.u_sat", "V", "saturation opening, increasing branch", kSaturationOpening,
       PNEUMAID_REF(valve.increasing.u_sat_V)},
      {"valve.decreasing.a", "-", "u^4 coefficient, decreasing branch", kAnyFinite,
       PNEUMAID_REF(valve.decreasing.a)},
      {"valve.decreasing.b", "-", "u^3 coefficient, decreasing branch", kAnyFinite,
       PNEUMAID_REF(valve.decreasing.b)},
      {"valve.decreasing.c", "-", "u^2 coefficient, decreasing branch", kAnyFinite,
       PNEUMAID_REF(valve.decreasing.c)},
      {"valve.decreasing.d", "-", "u coefficient, decreasing branch", kAnyFinite,
       PNEUMAID_REF(valve.decreasing.d)},
      {"valve.decreasing.q_max", "kg/s", "K_vp at saturation, decreasing branch", kPositive,
       PNEUMAID_REF(valve.decreasing.q_max_kg_per_s)},
      {"valve.decreasing.u_sat", "V", "saturation opening, decreasing branch", kSaturationOpening,
       PNEUMAID_REF(valve.decreasing.u_sat_V)},
      {"pipeline.delta", "1/s", "Eq. 5 rate constant at tube_length", kPositive,
       PNEUMAID_REF(pipeline.delta_per_s)},
      {"pipeline.tube_length", "m", "valve-to-cylinder tube length", kNonNegative,
       PNEUMAID_REF(pipeline.tube_length_m)},
      {"friction.positive.Fs", "N", "static friction, extending", kNonNegative,
       PNEUMAID_REF(friction.positive.static_force_N)},
      {"friction.positive.Fd", "N", "Coulomb (dynamic) friction, extending", kNonNegative,
       PNEUMAID_REF(friction.positive.dynamic_force_N)},
      {"friction.positive.b", "N s/m", "viscous coefficient, extending", kNonNegative,
       PNEUMAID_REF(friction.positive.viscous_N_s_per_m)},
      {"friction.positive.vs", "m/s", "Stribeck velocity, extending", kPositive,
       PNEUMAID_REF(friction.positive.stribeck_velocity_m_per_s)},
      {"friction.negative.Fs", "N", "static friction, retracting", kNonNegative,
       PNEUMAID_REF(friction.negative.static_force_N)},
      {"friction.negative.Fd", "N", "Coulomb (dynamic) friction, retracting", kNonNegative,
       PNEUMAID_REF(friction.negative.dynamic_force_N)},
      {"friction.negative.b", "N s/m", "viscous coefficient, retracting", kNonNegative,
       PNEUMAID_REF(friction.negative.viscous_N_s_per_m)},
      {"friction.negative.vs", "m/s", "Stribeck velocity, retracting", kPositive,
       PNEUMAID_REF(friction.negative.stribeck_velocity_m_per_s)},
  };
}

#undef PNEUMAID_REF

}  // namespace

bool ValueRange::Contains(double value) const {
  if (!std::isfinite(value)) return false;
  const bool above = min_inclusive ? value >= min : value > min;
  const bool below = max_inclusive ? value <= max : value < max;
  return above && below;
}

std::string ValueRange::Describe() const {
  std::ostringstream out;
  out << "a finite number";
  if (std::isfinite(min) || std::isfinite(max)) {
    out << " in " << (min_inclusive ? "[" : "(");
    if (std::isfinite(min))
      out << min;
    else
      out << "-inf";
    out << ", ";
    if (std::isfinite(max))
      out << max;
    else
      out << "inf";
    out << (max_inclusive ? "]" : ")");
  }
  return out.str();
}

const std::vector<ScalarParameterInfo>& ScalarParameterTable() {
  static const std::vector<ScalarParameterInfo> table = MakeTable();
  return table;
}

const ScalarParameterInfo* FindScalarParameter(const std::string& path) {
  for (const auto& info : ScalarParameterTable()) {
    if (path == info.path) return &info;
  }
  return nullptr;
}

bool GetParameter(const Parameters& params, const std::string& path, double* value) {
  if (const auto* info = FindScalarParameter(path)) {
    *value = info->get(params);
    return true;
  }
  std::string name, parameter;
  if (!SplitEffectPath(path, &name, &parameter)) return false;
  const auto effect = params.effects.find(name);
  if (effect == params.effects.end()) return false;
  const auto entry = effect->second.find(parameter);
  if (entry == effect->second.end()) return false;
  *value = entry->second;
  return true;
}

bool SetParameter(Parameters* params, const std::string& path, double value) {
  if (const auto* info = FindScalarParameter(path)) {
    info->ref(*params) = value;
    return true;
  }
  std::string name, parameter;
  if (!SplitEffectPath(path, &name, &parameter)) return false;
  const auto effect = params->effects.find(name);
  if (effect == params->effects.end()) return false;
  const auto entry = effect->second.find(parameter);
  if (entry == effect->second.end()) return false;
  entry->second = value;
  return true;
}

// 480 bytes with libstdc++ on x86-64 (GCC and Clang): a field added to
// Parameters changes it. Compare the new field in SameValues (a scalar of
// the table needs nothing), then update the size.
#if defined(__GLIBCXX__) && defined(__x86_64__)
static_assert(sizeof(Parameters) == 480,
              "Parameters changed: compare the new field in SameValues, then update this size");
#endif

bool SameValues(const Parameters& a, const Parameters& b) {
  for (const auto& info : ScalarParameterTable()) {
    if (!(info.get(a) == info.get(b))) return false;  // a NaN is apart
  }
  const auto same_entry = [](const DeltaAtLength& x, const DeltaAtLength& y) {
    return x.tube_length_m == y.tube_length_m && x.delta_per_s == y.delta_per_s;
  };
  const auto& la = a.pipeline.delta_by_length;
  const auto& lb = b.pipeline.delta_by_length;
  return a.cylinder.orientation == b.cylinder.orientation && a.valve.branch == b.valve.branch &&
         a.pipeline.model == b.pipeline.model && a.effects == b.effects &&
         std::equal(la.begin(), la.end(), lb.begin(), lb.end(), same_entry);
}

}  // namespace pneumaid
