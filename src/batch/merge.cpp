#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "pneumaid/batch/batch.h"
#include "pneumaid/io/files.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/json.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/model/parameter_table.h"

// `pneumaid merge`: the fleet summary of results directories (shards of one
// batch, or several batches): per parameter the median and a robust spread,
// units whose robust z-score exceeds the limit, every shard's failures.
namespace pneumaid {
namespace {

namespace fs = std::filesystem;

// The fleet's median: the mean of the two middle values for an even count
// (a fleet of two units is summarised by both), unlike the fits' upper
// median (src/util/median.h).
double Median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const std::size_t n = values.size();
  return n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

// Rows of a small CSV written by the batch (unit,... with quoted fields).
std::vector<std::vector<std::string>> ReadRows(const fs::path& file) {
  const std::string text = ReadTextFile(file.string(), "a batch table");
  std::vector<std::vector<std::string>> rows;
  std::vector<std::string> row;
  std::string field;
  bool quoted = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (quoted) {
      if (c == '"' && i + 1 < text.size() && text[i + 1] == '"') {
        field += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        field += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      row.push_back(field);
      field.clear();
    } else if (c == '\n') {
      row.push_back(field);
      field.clear();
      rows.push_back(row);
      row.clear();
    } else {
      field += c;
    }
  }
  if (!field.empty() || !row.empty()) {
    row.push_back(field);
    rows.push_back(row);
  }
  if (!rows.empty()) rows.erase(rows.begin());  // the header
  return rows;
}

std::string Format(double value) { return FormatSignificant(value, 6); }

}  // namespace

FleetSummary MergeResults(const std::vector<std::string>& results_dirs, double outlier_z) {
  FleetSummary summary;
  summary.outlier_z = outlier_z;
  std::vector<fs::path> seen;  // each directory once, however it was named
  for (const std::string& dir : results_dirs) {
    bool any = false;
    std::map<std::string, std::string> verdicts, statuses;
    std::error_code error;
    if (!fs::is_directory(dir, error)) {
      throw InputError(dir, 0, 0, "not a results directory (pneumaid batch --out)");
    }
    const fs::path canonical = fs::canonical(dir, error);
    if (std::find(seen.begin(), seen.end(), canonical) != seen.end()) continue;
    seen.push_back(canonical);
    for (const auto& entry : fs::directory_iterator(dir)) {
      const std::string name = entry.path().filename().string();
      if (entry.is_regular_file() && name.rfind("failures", 0) == 0 &&
          entry.path().extension() == ".csv") {
        any = true;
        for (const auto& row : ReadRows(entry.path())) {
          if (row.size() >= 2) summary.failures.push_back({row[0], row[1], entry.path().string()});
        }
      } else if (entry.is_regular_file() && name.rfind("summary", 0) == 0 &&
                 entry.path().extension() == ".csv") {
        any = true;
        for (const auto& row : ReadRows(entry.path())) {
          if (row.size() >= 3) verdicts[row[0]] = row[2], statuses[row[0]] = row[1];
        }
      }
    }
    for (const auto& entry : fs::directory_iterator(dir)) {
      const fs::path params = entry.path() / "params.yaml";
      const std::string name = entry.path().filename().string();
      // A unit's result is complete with its stamp; a killed run's temporary
      // or replaced directories (".tmp.") are not units.
      if (!entry.is_directory() || name.find(".tmp.") != std::string::npos || !fs::exists(params) ||
          !fs::exists(entry.path() / "stamp.txt"))
        continue;
      any = true;
      // An older result whose unit failed in the latest run is not current.
      // (One its summaries do not list stays: a run killed before it wrote
      // its summary, or a shard still running, has finished units too.)
      if (statuses.count(name) && statuses[name] == "failed") continue;
      const auto other = std::find_if(summary.units.begin(), summary.units.end(),
                                      [&name](const FleetUnit& u) { return u.unit == name; });
      if (other != summary.units.end()) {
        throw InputError(dir, 0, 0,
                         "unit '" + name + "' has results here and in " + other->results_dir +
                             ": a fleet summary takes each unit once");
      }
      FleetUnit unit;
      unit.unit = entry.path().filename().string();
      unit.results_dir = dir;
      unit.verdict = verdicts.count(unit.unit) ? verdicts[unit.unit] : "";
      const Parameters p = LoadParams(params.string());
      unit.standard_errors = p.uncertainty;
      for (const ScalarParameterInfo& info : ScalarParameterTable())
        unit.values[info.path] = info.get(p);
      for (const auto& [effect, values] : p.effects) {
        for (const auto& [name, value] : values)
          unit.values["effects." + effect + "." + name] = value;
      }
      summary.units.push_back(unit);
    }
    if (!any) throw InputError(dir, 0, 0, "not a results directory (pneumaid batch --out)");
  }
  std::sort(summary.units.begin(), summary.units.end(),
            [](const FleetUnit& a, const FleetUnit& b) { return a.unit < b.unit; });
  // A unit failed in one shard and done in another (a rerun) is not a failure.
  summary.failures.erase(
      std::remove_if(summary.failures.begin(), summary.failures.end(),
                     [&summary](const FleetFailure& f) {
                       return std::any_of(summary.units.begin(), summary.units.end(),
                                          [&f](const FleetUnit& u) { return u.unit == f.unit; });
                     }),
      summary.failures.end());
  std::map<std::string, std::vector<double>> by_path;
  for (const FleetUnit& u : summary.units) {
    for (const auto& [path, value] : u.values) by_path[path].push_back(value);
  }
  for (const auto& [path, values] : by_path) {
    FleetParameter parameter;
    parameter.path = path;
    parameter.units = static_cast<int>(values.size());
    parameter.median = Median(values);
    std::vector<double> deviations;
    for (double v : values) deviations.push_back(std::fabs(v - parameter.median));
    parameter.mad = 1.4826 * Median(deviations);
    summary.parameters.push_back(parameter);
    // Compared where at least 5 units have it and it varies at all (a
    // parameter from the prior is the same everywhere).
    const double floor = 1e-9 * std::fabs(parameter.median);
    if (parameter.units < 5 || !(parameter.mad > floor)) continue;
    for (FleetUnit& u : summary.units) {
      const auto found = u.values.find(path);
      if (found == u.values.end()) continue;
      // In units of the fleet's spread and the unit's own standard error
      // together: a coefficient its logs hardly determine (poorly separable
      // polynomial terms, a held Stribeck velocity) is no evidence.
      const auto error = u.standard_errors.find(path);
      // A unit whose set carries standard errors but none for this path did
      // not determine it (held, or from the prior): no evidence either way.
      if (error == u.standard_errors.end() && !u.standard_errors.empty()) continue;
      const double se = error == u.standard_errors.end() ? 0.0 : error->second;
      const double z = (found->second - parameter.median) / std::hypot(parameter.mad, se);
      if (std::fabs(z) > outlier_z) u.outlying.emplace_back(path, z);
    }
  }
  return summary;
}

std::string FleetSummary::Csv() const {
  std::ostringstream out;
  out << "unit,results,verdict,outlier,outlying_parameters";
  for (const FleetParameter& p : parameters) out << "," << p.path;
  out << "\n";
  for (const FleetUnit& u : units) {
    std::string outlying;
    for (const auto& [path, z] : u.outlying) outlying += (outlying.empty() ? "" : " ") + path;
    out << CsvField(u.unit) << "," << CsvField(u.results_dir) << "," << CsvField(u.verdict) << ","
        << (u.outlying.empty() ? "no" : "yes") << "," << outlying;
    for (const FleetParameter& p : parameters) {
      const auto found = u.values.find(p.path);
      // Every digit of the set (params.yaml's), for a program reading the table.
      out << "," << (found == u.values.end() ? "" : FormatDouble(found->second));
    }
    out << "\n";
  }
  for (const FleetFailure& f : failures) {
    out << CsvField(f.unit) << "," << CsvField(f.file) << "," << CsvField("FAILED: " + f.reason)
        << ",,";
    for (std::size_t k = 0; k < parameters.size(); ++k) out << ",";
    out << "\n";
  }
  out << "median,,,,";
  for (const FleetParameter& p : parameters) out << "," << FormatDouble(p.median);
  out << "\nmad,,,,";
  for (const FleetParameter& p : parameters) out << "," << FormatDouble(p.mad);
  out << "\n";
  return out.str();
}

std::string FleetSummary::Markdown() const {
  std::ostringstream out;
  out << "# Fleet summary\n\n"
      << units.size() << " units with a parameter set, " << failures.size()
      << " failed.\n\n## Outliers (robust z-score > " << Format(outlier_z) << ")\n\n";
  bool any = false;
  for (const FleetUnit& u : units) {
    if (u.outlying.empty()) continue;
    any = true;
    out << "- **" << u.unit << "**:";
    for (const auto& [path, z] : u.outlying) {
      char text[64];
      std::snprintf(text, sizeof(text), " z %+.1f", z);
      out << " " << path << text << " (" << Format(u.values.at(path)) << ")";
    }
    out << "\n";
  }
  if (!any) out << "none\n";
  out << "\n## Failures\n\n";
  for (const FleetFailure& f : failures) out << "- " << f.unit << ": " << f.reason << "\n";
  if (failures.empty()) out << "none\n";
  out << "\n## Units\n\n| unit | verdict | outlier |\n|---|---|---|\n";
  for (const FleetUnit& u : units) {
    out << "| " << u.unit << " | " << u.verdict << " | " << (u.outlying.empty() ? "" : "**yes**")
        << " |\n";
  }
  out << "\n## Parameters (varying across the fleet)\n\n| parameter | median | MAD (sigma) | "
         "units |\n|---|---|---|---|\n";
  for (const FleetParameter& p : parameters) {
    if (!(p.mad > 0)) continue;
    out << "| " << p.path << " | " << Format(p.median) << " | " << Format(p.mad) << " | " << p.units
        << " |\n";
  }
  return out.str();
}

}  // namespace pneumaid
