#include "pneumaid/io/units.h"

#include <algorithm>

namespace pneumaid {
namespace {

constexpr double kPsi_Pa = 6894.757293168361;  // 1 lbf/in^2

const std::vector<UnitInfo>& UnitTable() {
  static const std::vector<UnitInfo> table = {
      {"s", Quantity::kTime, 1.0, 0.0, false},
      {"ms", Quantity::kTime, 1e-3, 0.0, false},
      {"m", Quantity::kLength, 1.0, 0.0, false},
      {"cm", Quantity::kLength, 1e-2, 0.0, false},
      {"mm", Quantity::kLength, 1e-3, 0.0, false},
      {"Pa", Quantity::kPressure, 1.0, 0.0, false},
      {"kPa", Quantity::kPressure, 1e3, 0.0, false},
      {"MPa", Quantity::kPressure, 1e6, 0.0, false},
      {"bar", Quantity::kPressure, 1e5, 0.0, false},
      {"psi", Quantity::kPressure, kPsi_Pa, 0.0, false},
      {"Pa_g", Quantity::kPressure, 1.0, 0.0, true},
      {"kPa_g", Quantity::kPressure, 1e3, 0.0, true},
      {"MPa_g", Quantity::kPressure, 1e6, 0.0, true},
      {"bar_g", Quantity::kPressure, 1e5, 0.0, true},
      {"psi_g", Quantity::kPressure, kPsi_Pa, 0.0, true},
      {"m3/s", Quantity::kVolumetricFlow, 1.0, 0.0, false},
      {"l/min", Quantity::kVolumetricFlow, 1e-3 / 60.0, 0.0, false},
      {"L/min", Quantity::kVolumetricFlow, 1e-3 / 60.0, 0.0, false},
      {"m3/h", Quantity::kVolumetricFlow, 1.0 / 3600.0, 0.0, false},
      {"kg/s", Quantity::kMassFlow, 1.0, 0.0, false},
      {"g/s", Quantity::kMassFlow, 1e-3, 0.0, false},
      {"m3", Quantity::kVolume, 1.0, 0.0, false},
      {"cm3", Quantity::kVolume, 1e-6, 0.0, false},
      {"mm3", Quantity::kVolume, 1e-9, 0.0, false},
      {"kg", Quantity::kMass, 1.0, 0.0, false},
      {"g", Quantity::kMass, 1e-3, 0.0, false},
      {"V", Quantity::kCommand, 1.0, 0.0, false},
      {"K", Quantity::kTemperature, 1.0, 0.0, false},
      {"degC", Quantity::kTemperature, 1.0, 273.15, false},
  };
  return table;
}

}  // namespace

const UnitInfo* FindUnit(const std::string& symbol) {
  for (const auto& unit : UnitTable()) {
    if (symbol == unit.symbol) return &unit;
  }
  return nullptr;
}

std::string AcceptedUnits(const std::vector<Quantity>& quantities) {
  std::string out;
  for (const auto& unit : UnitTable()) {
    if (std::find(quantities.begin(), quantities.end(), unit.quantity) == quantities.end())
      continue;
    out += (out.empty() ? "" : ", ") + std::string(unit.symbol);
  }
  return out;
}

}  // namespace pneumaid
