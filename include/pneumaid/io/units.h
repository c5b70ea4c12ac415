// Unit strings of the rig-data format and their conversion to SI.
#pragma once

#include <string>
#include <vector>

namespace pneumaid {

enum class Quantity {
  kTime,
  kLength,
  kPressure,        // absolute and gauge units
  kVolumetricFlow,  // standard-referenced, converted to mass flow with the air density
  kMassFlow,
  kVolume,
  kMass,
  kCommand,
  kTemperature,
};

struct UnitInfo {
  const char* symbol;  // as written: "bar_g", "l/min"
  Quantity quantity;
  double scale;  // SI = value * scale + offset (+ p_atm for gauge pressures)
  double offset;
  bool gauge;
};

// nullptr for an unknown symbol.
const UnitInfo* FindUnit(const std::string& symbol);

// Symbols accepted for `quantity`, comma separated, for error messages.
std::string AcceptedUnits(const std::vector<Quantity>& quantities);

// Converts one value to SI; gauge pressures get `atmospheric_pressure_Pa` added.
inline double ToSI(const UnitInfo& unit, double value, double atmospheric_pressure_Pa) {
  return value * unit.scale + unit.offset + (unit.gauge ? atmospheric_pressure_Pa : 0.0);
}

}  // namespace pneumaid
