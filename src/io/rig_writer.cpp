#include "pneumaid/io/rig_writer.h"

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <sstream>

#include "pneumaid/io/files.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/json.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/units.h"
#include "provenance_map.h"

namespace pneumaid {
namespace {

namespace fs = std::filesystem;

// "<value in unit> <unit>" with the shortest round-trip decimal.
std::string WithUnit(double value_in_si, const char* unit) {
  const UnitInfo* info = FindUnit(unit);
  return "\"" + FormatDouble((value_in_si - info->offset) / info->scale) + " " + unit + "\"";
}

// A text scalar as the manifest writes it: plain, or double-quoted where
// another YAML reader would take it for other than text (a unit "0001") or
// it holds a character a flow mapping reads otherwise.
std::string Text(const std::string& text) {
  const bool plain = !ReadAsOtherThanText(text) &&
                     text.find_first_of(":,{}[]#&*!|>'\"%@`\\ ") == std::string::npos;
  return plain ? text : JsonString(text);
}

}  // namespace

double FromSI(const std::string& unit, double value_in_si, double atmospheric_pressure_Pa,
              double air_density_kg_per_m3) {
  const UnitInfo* info = FindUnit(unit);
  if (info == nullptr) throw InputError(unit, 0, 0, "unknown unit");
  double value = value_in_si;
  if (info->quantity == Quantity::kVolumetricFlow) value /= air_density_kg_per_m3;
  if (info->gauge) value -= atmospheric_pressure_Pa;
  return (value - info->offset) / info->scale;
}

std::string ManifestToYaml(const Manifest& manifest) {
  const RigConstants& r = manifest.rig;
  std::ostringstream out;
  out << "format: " << kRigFormat << "\n";
  out << "unit: " << Text(manifest.unit) << "\n";
  out << "rig:\n";
  out << "  gas: {k: " << FormatDouble(r.gas.heat_capacity_ratio)
      << ", R: " << FormatDouble(r.gas.gas_constant_J_per_kgK)
      << ", T: " << FormatDouble(r.gas.temperature_K) << "}\n";
  out << "  supply_pressure: " << WithUnit(r.supply_pressure_Pa, "bar") << "\n";
  out << "  atmospheric_pressure: " << FormatDouble(r.atmospheric_pressure_Pa) << "\n";
  out << "  air_density: " << FormatDouble(r.air_density_kg_per_m3) << "\n";
  out << "  cylinder:\n";
  out << "    bore: " << WithUnit(r.bore_m, "mm") << "\n";
  out << "    rod: " << WithUnit(r.rod_m, "mm") << "\n";
  out << "    stroke: " << WithUnit(r.stroke_m, "mm") << "\n";
  out << "    dead_volume_1: " << WithUnit(r.dead_volume_1_m3, "cm3") << "\n";
  out << "    dead_volume_2: " << WithUnit(r.dead_volume_2_m3, "cm3") << "\n";
  out << "  load_mass: " << WithUnit(r.load_mass_kg, "g") << "\n";
  out << "  orientation: " << ToString(r.orientation) << "\n";
  out << "  tube_length: " << WithUnit(r.tube_length_m, "cm") << "\n";
  out << "  position_origin: " << ToString(r.position_origin) << "\n";
  if (!manifest.sensors.empty()) {
    out << "sensors:\n";
    for (const auto& [name, sensor] : manifest.sensors) {
      out << "  " << name << ": {";
      const char* separator = "";
      if (sensor.tau_s) {
        out << "tau: " << FormatDouble(*sensor.tau_s);
        separator = ", ";
      }
      if (sensor.sigma) out << separator << "sigma: " << FormatDouble(*sensor.sigma);
      out << "}\n";
    }
  }
  out << "experiments:\n";
  for (const ExperimentEntry& entry : manifest.experiments) {
    out << "  - {id: " << Text(entry.id) << ", kind: " << ToString(entry.kind)
        << ", file: " << Text(entry.file);
    if (entry.tube_length_m) out << ", tube_length: " << WithUnit(*entry.tube_length_m, "cm");
    out << "}\n";
  }
  return out.str();
}

std::string RigLogToCsv(const RigLog& log) {
  std::ostringstream out;
  std::istringstream comment(log.comment);
  for (std::string line; std::getline(comment, line);) out << "# " << line << "\n";
  for (std::size_t i = 0; i < log.header.size(); ++i) out << (i ? "," : "") << log.header[i];
  out << "\n";
  const std::size_t rows = log.columns.empty() ? 0 : log.columns.front().size();
  for (std::size_t row = 0; row < rows; ++row) {
    for (std::size_t i = 0; i < log.columns.size(); ++i) {
      // 7 significant digits: what a rig's logger writes, and 10x below any noise level.
      out << (i ? "," : "") << FormatSignificant(log.columns[i][row], 7);
    }
    out << "\n";
  }
  return out.str();
}

void WriteDirectoryAtomically(const std::string& directory,
                              const std::map<std::string, std::string>& files) {
  const fs::path target(directory);
  if (fs::exists(target) && !(fs::is_directory(target) && fs::is_empty(target))) {
    throw InputError(directory, 0, 0, "output directory exists and is not empty; not overwriting");
  }
  ReplaceDirectoryAtomically(directory, files);  // `target` is absent or empty
}

}  // namespace pneumaid
