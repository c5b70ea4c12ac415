#include "pneumaid/io/rig_data.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <future>
#include <regex>
#include <set>

#include "pneumaid/io/csv_table.h"
#include "pneumaid/io/files.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/sha256.h"
#include "pneumaid/io/units.h"
#include "yaml_reader.h"

namespace pneumaid {
namespace {

namespace fs = std::filesystem;

constexpr double kPi = 3.14159265358979323846;
// A position more than this outside the stroke means a wrong origin or unit.
constexpr double kStrokeSlack_m = 1e-3;

// What a CSV column holds, by name.
struct ColumnInfo {
  const char* name;
  std::vector<Quantity> quantities;  // accepted; the first is the SI meaning of a bare header
};

const std::vector<ColumnInfo>& KnownColumns() {
  static const std::vector<ColumnInfo> columns = {
      {"t", {Quantity::kTime}},
      {"u", {Quantity::kCommand}},
      {"x", {Quantity::kLength}},
      {"p_up", {Quantity::kPressure}},
      {"p_down", {Quantity::kPressure}},
      {"p_in", {Quantity::kPressure}},
      {"p_out", {Quantity::kPressure}},
      {"p1", {Quantity::kPressure}},
      {"p2", {Quantity::kPressure}},
      {"q", {Quantity::kVolumetricFlow, Quantity::kMassFlow}},
      {"q_in", {Quantity::kVolumetricFlow, Quantity::kMassFlow}},
      {"q_out", {Quantity::kVolumetricFlow, Quantity::kMassFlow}},
      {"q1", {Quantity::kVolumetricFlow, Quantity::kMassFlow}},
      {"q2", {Quantity::kVolumetricFlow, Quantity::kMassFlow}},
  };
  return columns;
}

const ColumnInfo* FindColumn(const std::string& name) {
  for (const auto& column : KnownColumns()) {
    if (name == column.name) return &column;
  }
  return nullptr;
}

struct KindColumns {
  std::vector<std::string> required, optional;
};

KindColumns ColumnsOf(ExperimentKind kind) {
  switch (kind) {
    case ExperimentKind::kValve:
      return {{"t", "u", "p_up", "p_down", "q"}, {}};
    case ExperimentKind::kPipeline:
      return {{"t", "u", "q_in", "q_out"}, {"p_in", "p_out"}};
    case ExperimentKind::kStroke:
    case ExperimentKind::kValidation:
      return {{"t", "u", "x", "p1", "p2"}, {"q1", "q2"}};
  }
  return {};
}

// Reads the manifest, remembering nothing but what it returns.
class ManifestReader : internal::YamlReader {
 public:
  explicit ManifestReader(std::string source) : YamlReader(std::move(source)) {}

  Manifest Read(const std::string& text) {
    return Guarded([&] { return ReadDocument(text); });
  }

 private:
  Manifest ReadDocument(const std::string& text) {
    const YAML::Node root =
        LoadMapping(text, "expected a mapping starting with format: pneumaid-rig/1");
    const std::set<std::string> known = {"format", "unit", "rig", "sensors", "experiments"};
    for (const auto& entry : root) {
      const std::string key = Key(entry.first);
      if (!known.count(key))
        Fail(entry.first,
             "unknown key '" + key + "' (expected " + "format, unit, rig, sensors, experiments)");
      NotEmpty(entry.first, entry.second, key);
    }
    for (const char* key : {"format", "unit", "experiments"}) {
      if (!root[key]) Fail(root, std::string("missing required key '") + key + "'");
    }
    if (Text(root["format"], "format") != kRigFormat) {
      Fail(root["format"], std::string("expected format: ") + kRigFormat);
    }
    Manifest manifest;
    manifest.unit = Text(root["unit"], "unit");
    if (!IsUnitId(manifest.unit)) {
      Fail(root["unit"], "unit: expected an id of letters, digits, '.', '_' or '-'");
    }
    ReadRig(root["rig"], &manifest);
    if (root["sensors"]) ReadSensors(root["sensors"], manifest.rig, &manifest);
    ReadExperiments(root["experiments"], &manifest);
    return manifest;
  }

  std::string Text(const YAML::Node& node, const std::string& path) const {
    return Scalar(node, path);
  }

  // A number in SI units, or "<number> <unit>" with a unit of `quantity`.
  // Gauge pressures get `atmospheric_Pa` added; `scale_only` converts a
  // difference (noise levels): no offset, no gauge.
  double ScalarInSI(const YAML::Node& node, const std::string& path,
                    const std::vector<Quantity>& quantities, double atmospheric_Pa,
                    bool scale_only = false) const {
    const std::string text = Text(node, path);
    double number = 0;
    const char* end = internal::ParseNumber(text.c_str(), text.c_str() + text.size(), &number);
    if (end == nullptr) Fail(node, path + ": expected a number or '<number> <unit>'");
    std::string rest(end);
    while (!rest.empty() && rest.front() == ' ') rest.erase(rest.begin());
    if (!std::isfinite(number)) Fail(node, path + ": expected a finite number");
    if (rest.empty()) return number;
    const UnitInfo* unit = FindUnit(rest);
    bool accepted = false;
    for (Quantity q : quantities) accepted = accepted || (unit != nullptr && unit->quantity == q);
    if (!accepted) {
      const std::string units = AcceptedUnits(quantities);
      Fail(node, path + ": unit '" + rest + "' not accepted" +
                     (units.empty() ? std::string("; expected a plain number in SI units")
                                    : "; expected one of " + units));
    }
    if (scale_only) return number * unit->scale;
    return ToSI(*unit, number, atmospheric_Pa);
  }

  void CheckPositive(const YAML::Node& node, const std::string& path, double value) const {
    if (!(value > 0)) Fail(node, path + ": non-physical value, expected > 0");
  }

  // rig: every key optional; missing keys take the paper's values and are
  // listed in defaults_used.
  void ReadRig(const YAML::Node& rig, Manifest* manifest) {
    RigConstants& r = manifest->rig;
    if (rig && !rig.IsMap()) Fail(rig, "rig: expected a mapping");
    const YAML::Node empty(YAML::NodeType::Undefined);  // "absent", unlike Node() (null)
    const auto child = [&](const YAML::Node& parent, const char* key) {
      return parent && parent.IsMap() ? parent[key] : empty;
    };
    if (rig)
      Keys(rig, "rig.",
           {"gas", "supply_pressure", "atmospheric_pressure", "air_density", "cylinder",
            "load_mass", "orientation", "tube_length", "position_origin"});
    const YAML::Node gas = child(rig, "gas");
    const YAML::Node cylinder = child(rig, "cylinder");
    if (gas) Keys(gas, "rig.gas.", {"k", "R", "T"});
    if (cylinder)
      Keys(cylinder, "rig.cylinder.", {"bore", "rod", "stroke", "dead_volume_1", "dead_volume_2"});

    // Atmospheric pressure first: gauge values elsewhere need it.
    ReadScalar(child(rig, "atmospheric_pressure"), "rig.atmospheric_pressure",
               {Quantity::kPressure}, &r.atmospheric_pressure_Pa, manifest, true);
    const double p_atm = r.atmospheric_pressure_Pa;
    ReadScalar(child(gas, "k"), "rig.gas.k", {}, &r.gas.heat_capacity_ratio, manifest);
    ReadScalar(child(gas, "R"), "rig.gas.R", {}, &r.gas.gas_constant_J_per_kgK, manifest);
    ReadScalar(child(gas, "T"), "rig.gas.T", {Quantity::kTemperature}, &r.gas.temperature_K,
               manifest);
    ReadScalar(child(rig, "supply_pressure"), "rig.supply_pressure", {Quantity::kPressure},
               &r.supply_pressure_Pa, manifest, false, p_atm);
    ReadScalar(child(rig, "air_density"), "rig.air_density", {}, &r.air_density_kg_per_m3,
               manifest);
    ReadScalar(child(cylinder, "bore"), "rig.cylinder.bore", {Quantity::kLength}, &r.bore_m,
               manifest);
    ReadScalar(child(cylinder, "rod"), "rig.cylinder.rod", {Quantity::kLength}, &r.rod_m, manifest);
    ReadScalar(child(cylinder, "stroke"), "rig.cylinder.stroke", {Quantity::kLength}, &r.stroke_m,
               manifest);
    ReadScalar(child(cylinder, "dead_volume_1"), "rig.cylinder.dead_volume_1", {Quantity::kVolume},
               &r.dead_volume_1_m3, manifest);
    ReadScalar(child(cylinder, "dead_volume_2"), "rig.cylinder.dead_volume_2", {Quantity::kVolume},
               &r.dead_volume_2_m3, manifest);
    ReadScalar(child(rig, "load_mass"), "rig.load_mass", {Quantity::kMass}, &r.load_mass_kg,
               manifest);
    ReadScalar(child(rig, "tube_length"), "rig.tube_length", {Quantity::kLength}, &r.tube_length_m,
               manifest);
    ReadChoice(child(rig, "orientation"), "rig.orientation",
               {{"vertical", Orientation::kVertical}, {"horizontal", Orientation::kHorizontal}},
               &r.orientation, manifest);
    ReadChoice(child(rig, "position_origin"), "rig.position_origin",
               {{"mid", PositionOrigin::kMid}, {"retracted", PositionOrigin::kRetracted}},
               &r.position_origin, manifest);
    CheckRigPhysics(rig, gas, cylinder, child, r);
  }

  template <typename Child>
  void CheckRigPhysics(const YAML::Node& rig, const YAML::Node& gas, const YAML::Node& cylinder,
                       const Child& child, const RigConstants& r) const {
    const auto where = [&](const YAML::Node& node) { return node ? node : rig; };
    if (!(r.gas.heat_capacity_ratio > 1 && r.gas.heat_capacity_ratio <= 3)) {
      Fail(where(child(gas, "k")), "rig.gas.k: non-physical value, expected in (1, 3]");
    }
    CheckPositive(where(child(gas, "R")), "rig.gas.R", r.gas.gas_constant_J_per_kgK);
    CheckPositive(where(child(gas, "T")), "rig.gas.T", r.gas.temperature_K);
    CheckPositive(where(child(rig, "atmospheric_pressure")), "rig.atmospheric_pressure",
                  r.atmospheric_pressure_Pa);
    if (!(r.supply_pressure_Pa > r.atmospheric_pressure_Pa)) {
      Fail(where(child(rig, "supply_pressure")),
           "rig.supply_pressure: non-physical value, expected above the atmospheric pressure "
           "(both absolute)");
    }
    CheckPositive(where(child(rig, "air_density")), "rig.air_density", r.air_density_kg_per_m3);
    CheckPositive(where(child(cylinder, "bore")), "rig.cylinder.bore", r.bore_m);
    CheckPositive(where(child(cylinder, "rod")), "rig.cylinder.rod", r.rod_m);
    if (!(r.rod_m < r.bore_m)) {
      Fail(where(child(cylinder, "rod")), "rig.cylinder.rod: expected a rod smaller than the bore");
    }
    CheckPositive(where(child(cylinder, "stroke")), "rig.cylinder.stroke", r.stroke_m);
    CheckPositive(where(child(cylinder, "dead_volume_1")), "rig.cylinder.dead_volume_1",
                  r.dead_volume_1_m3);
    CheckPositive(where(child(cylinder, "dead_volume_2")), "rig.cylinder.dead_volume_2",
                  r.dead_volume_2_m3);
    CheckPositive(where(child(rig, "load_mass")), "rig.load_mass", r.load_mass_kg);
    CheckPositive(where(child(rig, "tube_length")), "rig.tube_length", r.tube_length_m);
  }

  void ReadScalar(const YAML::Node& node, const std::string& path,
                  const std::vector<Quantity>& quantities, double* value, Manifest* manifest,
                  bool absolute_only = false, double atmospheric_Pa = 0) const {
    if (!node) {
      manifest->defaults_used.push_back(path);
      return;
    }
    manifest->lines[path] = node.Mark().line + 1;
    if (absolute_only) {
      const std::string text = Text(node, path);
      if (text.find("_g") != std::string::npos)
        Fail(node, path + ": expected an absolute pressure");
    }
    *value = ScalarInSI(node, path, quantities, atmospheric_Pa);
  }

  template <typename Enum>
  void ReadChoice(const YAML::Node& node, const std::string& path,
                  const std::vector<std::pair<std::string, Enum>>& choices, Enum* value,
                  Manifest* manifest) const {
    if (!node) {
      manifest->defaults_used.push_back(path);
      return;
    }
    manifest->lines[path] = node.Mark().line + 1;
    const std::string text = Text(node, path);
    std::vector<std::string> names;
    for (const auto& [name, choice] : choices) {
      if (text == name) {
        *value = choice;
        return;
      }
      names.push_back(name);
    }
    Fail(node, path + ": expected one of " + internal::JoinNames(names) + ", got '" + text + "'");
  }

  void ReadSensors(const YAML::Node& sensors, const RigConstants& rig, Manifest* manifest) const {
    if (!sensors.IsMap()) Fail(sensors, "sensors: expected a mapping column -> {tau, sigma}");
    for (const auto& entry : sensors) {
      const std::string name = Key(entry.first);
      NotEmpty(entry.first, entry.second, "sensors." + name);
      const ColumnInfo* column = FindColumn(name);
      if (column == nullptr) {
        std::vector<std::string> names;
        for (const auto& known : KnownColumns()) names.push_back(known.name);
        Fail(entry.first, "sensors: unknown column '" + name + "' (expected one of " +
                              internal::JoinNames(names) + ")");
      }
      const std::string path = "sensors." + name;
      Keys(entry.second, path + ".", {"tau", "sigma"});
      SensorInfo info;
      if (const YAML::Node tau = entry.second["tau"]) {
        info.tau_s = ScalarInSI(tau, path + ".tau", {Quantity::kTime}, 0.0);
        if (!(*info.tau_s >= 0)) Fail(tau, path + ".tau: expected >= 0 s");
      }
      if (const YAML::Node sigma = entry.second["sigma"]) {
        info.sigma = SigmaInSI(sigma, path + ".sigma", *column, rig);
        if (!(*info.sigma >= 0)) Fail(sigma, path + ".sigma: expected >= 0");
      }
      manifest->sensors[name] = info;
    }
  }

  // A flow noise level as a bare number is standard volumetric flow [m3/s],
  // stored as mass flow; with a mass-flow unit it is taken as it stands.
  double SigmaInSI(const YAML::Node& node, const std::string& path, const ColumnInfo& column,
                   const RigConstants& rig) const {
    const double value = ScalarInSI(node, path, column.quantities, 0.0, /*scale_only=*/true);
    if (column.quantities.front() != Quantity::kVolumetricFlow) return value;
    const std::string text = Text(node, path);
    const bool mass_unit = text.find("g/s") != std::string::npos;
    return mass_unit ? value : value * rig.air_density_kg_per_m3;
  }

  void ReadExperiments(const YAML::Node& list, Manifest* manifest) const {
    if (!list.IsSequence() || list.size() == 0) {
      Fail(list, "experiments: expected a list of at least one {id, kind, file}");
    }
    std::set<std::string> ids;
    for (const auto& item : list) {
      if (!item.IsMap()) Fail(item, "experiments: expected {id, kind, file}");
      Keys(item, "experiments[].", {"id", "kind", "file", "tube_length"});
      for (const char* key : {"id", "kind", "file"}) {
        if (!item[key]) Fail(item, std::string("experiment: missing required key '") + key + "'");
      }
      ExperimentEntry entry;
      entry.manifest_line = item.Mark().line + 1;
      entry.id = Text(item["id"], "experiments[].id");
      if (entry.id.empty()) Fail(item["id"], "experiment id: expected a non-empty id");
      if (!ids.insert(entry.id).second) {
        Fail(item["id"], "duplicate experiment id '" + entry.id + "'");
      }
      entry.kind = Kind(item["kind"]);
      entry.file = Text(item["file"], "experiments[].file");
      CheckRelativeFile(item["file"], entry.file);
      if (const YAML::Node length = item["tube_length"]) {
        if (entry.kind != ExperimentKind::kPipeline) {
          Fail(length, "tube_length: only pipeline experiments have one");
        }
        entry.tube_length_m = ScalarInSI(length, "tube_length", {Quantity::kLength}, 0.0);
        CheckPositive(length, "tube_length", *entry.tube_length_m);
      } else if (entry.kind == ExperimentKind::kPipeline) {
        Fail(item, "pipeline experiment '" + entry.id + "': missing required key 'tube_length'");
      }
      manifest->experiments.push_back(entry);
    }
  }

  ExperimentKind Kind(const YAML::Node& node) const {
    const std::string text = Text(node, "kind");
    for (ExperimentKind kind : {ExperimentKind::kValve, ExperimentKind::kPipeline,
                                ExperimentKind::kStroke, ExperimentKind::kValidation}) {
      if (text == ToString(kind)) return kind;
    }
    Fail(node, "kind: expected valve | pipeline | stroke | validation, got '" + text + "'");
  }

  void CheckRelativeFile(const YAML::Node& node, const std::string& file) const {
    const fs::path path(file);
    if (file.empty() || path.is_absolute()) {
      Fail(node, "file '" + file + "': expected a path relative to the unit directory");
    }
    const fs::path normal = path.lexically_normal();
    if (normal.empty() || *normal.begin() == ".." || normal == ".") {
      Fail(node, "file '" + file + "': resolves outside the unit directory");
    }
  }
};

// Converts one CSV column to SI, checking its unit against what the name
// holds. Takes the column's values (they are converted in place).
std::vector<double> ColumnToSI(const CsvTable& table, CsvColumn& column, const ColumnInfo& info,
                               const Manifest& manifest) {
  const RigConstants& rig = manifest.rig;
  std::vector<double> values = std::move(column.values);
  if (column.unit.empty()) {
    if (info.quantities.front() == Quantity::kVolumetricFlow) {
      for (double& v : values) v *= rig.air_density_kg_per_m3;  // bare header: m3/s
    }
    return values;
  }
  const UnitInfo* unit = FindUnit(column.unit);
  bool accepted = false;
  for (Quantity q : info.quantities) accepted = accepted || (unit && unit->quantity == q);
  if (!accepted) {
    throw InputError(table.file, table.header_line, column.column,
                     "column '" + column.name + "': unit '" + column.unit +
                         "' not accepted; expected one of " + AcceptedUnits(info.quantities));
  }
  const double density =
      unit->quantity == Quantity::kVolumetricFlow ? rig.air_density_kg_per_m3 : 1.0;
  for (double& v : values) v = ToSI(*unit, v, rig.atmospheric_pressure_Pa) * density;
  return values;
}

void CheckIncreasingTime(const CsvTable& table, const CsvColumn& column,
                         const std::vector<double>& t) {
  for (std::size_t i = 1; i < t.size(); ++i) {
    if (!(t[i] > t[i - 1])) {
      throw InputError(table.file, table.row_lines[i], column.column,
                       "column 't': expected strictly increasing time, got " +
                           std::to_string(t[i]) + " s after " + std::to_string(t[i - 1]) + " s");
    }
  }
}

void CheckCommandRange(const CsvTable& table, const CsvColumn& column, const std::vector<double>& u,
                       ExperimentKind kind) {
  const bool bidirectional = kind == ExperimentKind::kStroke || kind == ExperimentKind::kValidation;
  const double low = bidirectional ? -1.0 : 0.0;
  for (std::size_t i = 0; i < u.size(); ++i) {
    if (u[i] < low - 1e-9 || u[i] > 1.0 + 1e-9) {
      char got[32];
      std::snprintf(got, sizeof(got), "%.9g", u[i]);
      throw InputError(table.file, table.row_lines[i], column.column,
                       std::string("column 'u': expected a command in [") +
                           (bidirectional ? "-1" : "0") + ", 1] V, got " + got);
    }
  }
}

// Shifts x to mid-stroke origin and rejects positions off the stroke.
void PlacePositions(const CsvTable& table, const CsvColumn& column, const Manifest& manifest,
                    std::vector<double>* x) {
  const double half = 0.5 * manifest.rig.stroke_m;
  const double shift = manifest.rig.position_origin == PositionOrigin::kRetracted ? -half : 0.0;
  for (std::size_t i = 0; i < x->size(); ++i) {
    (*x)[i] += shift;
    if (std::fabs((*x)[i]) > half + kStrokeSlack_m) {
      throw InputError(
          table.file, table.row_lines[i], column.column,
          "column 'x': position " + std::to_string(((*x)[i] - shift) * 1e3) +
              " mm (as logged) is more than 1 mm outside the stroke with position_origin: " +
              ToString(manifest.rig.position_origin) + "; check the origin and the unit");
    }
  }
}

}  // namespace

std::vector<std::string> SimulableRuns(const Unit& unit) {
  std::vector<std::string> ids;
  for (const Experiment& e : unit.experiments) {
    if (IsSimulable(e.entry.kind)) ids.push_back(e.entry.id);
  }
  return ids;
}

bool IsSimulable(ExperimentKind kind) {
  return kind == ExperimentKind::kStroke || kind == ExperimentKind::kValidation;
}

const char* ToString(ExperimentKind kind) {
  switch (kind) {
    case ExperimentKind::kValve:
      return "valve";
    case ExperimentKind::kPipeline:
      return "pipeline";
    case ExperimentKind::kStroke:
      return "stroke";
    case ExperimentKind::kValidation:
      return "validation";
  }
  return "?";
}

const char* ToString(PositionOrigin origin) {
  return origin == PositionOrigin::kMid ? "mid" : "retracted";
}

double RigConstants::area_1_m2() const { return 0.25 * kPi * bore_m * bore_m; }
double RigConstants::area_2_m2() const { return area_1_m2() - 0.25 * kPi * rod_m * rod_m; }

double Manifest::DeclaredSigma(const std::string& column, double fallback) const {
  const auto found = sensors.find(column);
  return found != sensors.end() && found->second.sigma ? *found->second.sigma : fallback;
}

double Manifest::DeclaredTau(const std::string& column, double fallback) const {
  const auto found = sensors.find(column);
  return found != sensors.end() && found->second.tau_s ? *found->second.tau_s : fallback;
}

std::size_t Experiment::samples() const { return column("t").size(); }

const std::vector<double>& Experiment::column(const std::string& name) const {
  static const std::vector<double> kEmpty;
  const auto found = columns.find(name);
  return found == columns.end() ? kEmpty : found->second;
}

Trajectory Experiment::AsTrajectory() const {
  Trajectory out;
  out.t_s = column("t");
  out.u_V = column("u");
  out.x_m = column("x");
  out.p1_Pa = column("p1");
  out.p2_Pa = column("p2");
  out.q1_kg_per_s = column("q1");
  out.q2_kg_per_s = column("q2");
  return out;
}

Manifest ParseManifest(const std::string& text, const std::string& source) {
  return ManifestReader(source).Read(text);
}

Experiment ParseExperiment(const std::string& text, const std::string& path,
                           const ExperimentEntry& entry, const Manifest& manifest,
                           const ReadOptions& options) {
  // Hashed on the other core while this one parses (reading stays
  // I/O-bound), or here after parsing.
  std::future<std::string> sha256;
  if (options.hash_on_second_thread)
    sha256 = std::async(std::launch::async, Sha256Hex, std::cref(text));
  CsvTable table = ParseCsv(text, path);
  const KindColumns kind_columns = ColumnsOf(entry.kind);
  for (const auto& name : kind_columns.required) {
    if (table.Find(name) == nullptr) {
      throw InputError(path, table.header_line, 0,
                       "missing column '" + name + "': a " + ToString(entry.kind) + " log needs " +
                           internal::JoinNames(kind_columns.required));
    }
  }
  Experiment out;
  out.entry = entry;
  out.path = path;
  out.unterminated_last_row = table.unterminated_last_row;

  std::set<std::string> wanted(kind_columns.required.begin(), kind_columns.required.end());
  wanted.insert(kind_columns.optional.begin(), kind_columns.optional.end());
  for (CsvColumn& column : table.columns) {
    if (!wanted.count(column.name)) {
      out.ignored_columns.push_back(column.name);
      continue;
    }
    std::vector<double> values = ColumnToSI(table, column, *FindColumn(column.name), manifest);
    if (column.name == "t") CheckIncreasingTime(table, column, values);
    if (column.name == "u") CheckCommandRange(table, column, values, entry.kind);
    if (column.name == "x") PlacePositions(table, column, manifest, &values);
    out.units_as_written[column.name] = column.unit;
    out.columns[column.name] = std::move(values);
  }
  // Time counts from the log's first sample: a logger's absolute clock (Unix
  // time, 1.7e9 s, resolved to 2.4e-7 s) leaves the simulator no digits for
  // its steps.
  std::vector<double>& t = out.columns.at("t");
  out.time_origin_s = t.front();
  for (double& value : t) value -= out.time_origin_s;
  out.sha256 = sha256.valid() ? sha256.get() : Sha256Hex(text);
  return out;
}

Unit ReadUnit(const std::string& directory, const ReadOptions& options) {
  const fs::path dir(directory);
  const std::string manifest_path = (dir / "unit.yaml").string();
  if (!fs::is_directory(dir)) throw InputError(directory, 0, 0, "not a unit directory");
  Unit unit;
  unit.directory = directory;
  unit.manifest = ParseManifest(ReadTextFile(manifest_path, "manifest"), manifest_path);
  const fs::path root = fs::weakly_canonical(dir);
  for (const ExperimentEntry& entry : unit.manifest.experiments) {
    const fs::path file = dir / entry.file;
    const fs::path resolved = fs::weakly_canonical(file);
    const auto [root_end, unused] = std::mismatch(root.begin(), root.end(), resolved.begin());
    if (root_end != root.end()) {
      throw InputError(manifest_path, entry.manifest_line, 0,
                       "experiment '" + entry.id + "': file '" + entry.file +
                           "' resolves outside the unit directory");
    }
    if (!fs::is_regular_file(file)) {
      throw InputError(manifest_path, entry.manifest_line, 0,
                       "experiment '" + entry.id + "': file '" + entry.file + "' not found");
    }
    unit.experiments.push_back(ParseExperiment(ReadTextFile(file.string(), "CSV file"),
                                               file.string(), entry, unit.manifest, options));
  }
  return unit;
}

std::optional<Experiment> ReadLogOfUnit(const std::string& csv_path) {
  const fs::path log = fs::weakly_canonical(csv_path);
  const fs::path manifest_path = log.parent_path() / "unit.yaml";
  if (!fs::is_regular_file(manifest_path)) return std::nullopt;
  const Manifest manifest =
      ParseManifest(ReadTextFile(manifest_path.string(), "manifest"), manifest_path.string());
  for (const ExperimentEntry& entry : manifest.experiments) {
    if (fs::weakly_canonical(log.parent_path() / entry.file) != log) continue;
    return ParseExperiment(ReadTextFile(csv_path, "CSV file"), csv_path, entry, manifest);
  }
  return std::nullopt;
}

bool IsUnitId(const std::string& id) {
  static const std::regex kUnitId("[A-Za-z0-9._-]+");
  return std::regex_match(id, kUnitId);
}

std::vector<std::string> FleetUnits(const std::string& fleet_directory,
                                    std::vector<std::string>* not_units) {
  std::vector<std::string> units, others;
  if (!fs::is_directory(fleet_directory)) {
    throw InputError(fleet_directory, 0, 0, "not a fleet directory");
  }
  for (const auto& entry : fs::directory_iterator(fleet_directory)) {
    // Hidden ones (.git, .snapshot) are neither units nor worth a word.
    if (!entry.is_directory() || entry.path().filename().string().front() == '.') continue;
    (fs::exists(entry.path() / "unit.yaml") ? units : others).push_back(entry.path().string());
  }
  std::sort(units.begin(), units.end());
  std::sort(others.begin(), others.end());
  if (not_units != nullptr) *not_units = others;
  return units;
}

}  // namespace pneumaid
