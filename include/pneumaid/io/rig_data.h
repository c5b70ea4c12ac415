// The rig-data format `pneumaid-rig/1` (docs/data-format.md): a unit
// directory with a manifest (unit.yaml) and one CSV file per experiment, read
// into typed experiments in SI units (x from mid-stroke, absolute pressures,
// mass flows). Every violation of the format throws one InputError naming the
// file, line and column.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "pneumaid/model/parameters.h"
#include "pneumaid/trajectory.h"

namespace pneumaid {

inline constexpr const char* kRigFormat = "pneumaid-rig/1";

enum class ExperimentKind { kValve, kPipeline, kStroke, kValidation };
enum class PositionOrigin { kMid, kRetracted };

const char* ToString(ExperimentKind kind);

// Stroke and validation runs can be simulated (the whole actuator from a
// logged start); valve and tube logs cannot. The one home of that rule.
bool IsSimulable(ExperimentKind kind);
const char* ToString(PositionOrigin origin);

// Rig constants of the manifest, SI. Defaults are the seed paper's values.
struct RigConstants {
  GasParams gas;
  double supply_pressure_Pa = 5.0e5;
  double atmospheric_pressure_Pa = 1.0e5;
  double air_density_kg_per_m3 = 1.178;  // volumetric (standard) flow -> mass flow
  double bore_m = 0.016;
  double rod_m = 0.006;
  double stroke_m = 0.05;
  double dead_volume_1_m3 = 1.01e-7;
  double dead_volume_2_m3 = 8.65e-8;
  double load_mass_kg = 0.15;
  Orientation orientation = Orientation::kVertical;
  double tube_length_m = 0.38;
  PositionOrigin position_origin = PositionOrigin::kMid;

  double area_1_m2() const;  // pi bore^2 / 4
  double area_2_m2() const;  // area_1 - pi rod^2 / 4
};

// What the manifest says about one instrument (a CSV column name).
struct SensorInfo {
  std::optional<double> tau_s;  // first-order lag
  std::optional<double> sigma;  // noise std in SI units of the column as read (mass flow for flows)
};

struct ExperimentEntry {
  std::string id;
  ExperimentKind kind = ExperimentKind::kValidation;
  std::string file;                     // as written, relative to the unit directory
  std::optional<double> tube_length_m;  // pipeline experiments
  int manifest_line = 0;
};

struct Manifest {
  std::string unit;
  RigConstants rig;
  std::map<std::string, SensorInfo> sensors;
  std::vector<ExperimentEntry> experiments;
  std::vector<std::string> defaults_used;  // rig keys that took their default
  std::map<std::string, int> lines;        // rig keys written -> their line in unit.yaml

  // What the sensors block declares for a column's instrument, or `fallback`.
  double DeclaredSigma(const std::string& column, double fallback) const;
  double DeclaredTau(const std::string& column, double fallback) const;
};

struct Experiment {
  ExperimentEntry entry;
  std::string path;    // the file read
  std::string sha256;  // of its bytes
  // SI columns by name: t [s, from the log's first sample], u [V], x [m from
  // mid-stroke], pressures [Pa absolute], flows [kg/s]. Only the columns of
  // the kind's table.
  std::map<std::string, std::vector<double>> columns;
  std::map<std::string, std::string> units_as_written;  // column -> unit in the header ("" = SI)
  std::vector<std::string> ignored_columns;
  bool unterminated_last_row = false;  // CsvTable::unterminated_last_row
  double time_origin_s = 0;            // the logged time of the first sample (t = 0 here)

  std::size_t samples() const;
  const std::vector<double>& column(const std::string& name) const;  // empty when absent
  // t, u, x, p1, p2 (and q1, q2 when logged) as a Trajectory; v stays empty.
  Trajectory AsTrajectory() const;
};

struct Unit {
  std::string directory;
  Manifest manifest;
  std::vector<Experiment> experiments;

  // The manifest's path, for messages.
  std::string manifest_path() const { return directory + "/unit.yaml"; }
};

// Whether `id` is a unit id as the rig format has it ([A-Za-z0-9._-]+): a
// manifest's `unit`, and a parameter set's.
bool IsUnitId(const std::string& id);

// The ids of a unit's simulable runs (IsSimulable), in the manifest's order.
std::vector<std::string> SimulableRuns(const Unit& unit);

// Parses a manifest's text; `source` names it in messages.
Manifest ParseManifest(const std::string& text, const std::string& source);

// How logs are read.
struct ReadOptions {
  // Each log's SHA-256 (Experiment::sha256, for provenance) is computed on a
  // second thread while this one parses the log (a lone read is then bound by
  // the parsing alone); false: on this thread (a batch worker, whose threads
  // are all the busy threads it may have).
  bool hash_on_second_thread = true;
};

// Reads unit.yaml and every experiment file of a unit directory.
Unit ReadUnit(const std::string& directory, const ReadOptions& options = {});

// Converts the columns of one experiment file of `entry` (already parsed as CSV
// text) to SI; `manifest` supplies atmospheric pressure, air density, stroke
// and position origin.
Experiment ParseExperiment(const std::string& text, const std::string& path,
                           const ExperimentEntry& entry, const Manifest& manifest,
                           const ReadOptions& options = {});

// When `csv_path` is one of the logs listed in the unit.yaml beside it, that
// log read as its unit's manifest says (origin, units, gauge pressures);
// otherwise nothing. Throws InputError for a malformed manifest or log.
std::optional<Experiment> ReadLogOfUnit(const std::string& csv_path);

// The unit directories of a fleet directory (its immediate subdirectories that
// hold a unit.yaml), sorted by name; `not_units` (may be null) gets the
// other subdirectories, sorted, for a caller to say that it skipped them.
std::vector<std::string> FleetUnits(const std::string& fleet_directory,
                                    std::vector<std::string>* not_units = nullptr);

}  // namespace pneumaid
