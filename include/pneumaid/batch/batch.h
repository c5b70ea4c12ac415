// Fleet work: every unit of a fleet directory identified (and refined,
// validated, diagnosed when asked) into a results directory, on worker
// threads, as one shard of a cluster job, resumable after a kill. Units are
// independent; a unit that fails is recorded and the others carry on.
// docs/batch.md gives the recipes (one machine, Slurm, mpirun, GNU parallel).
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "pneumaid/diagnose/diagnose.h"
#include "pneumaid/ident/fit_spec.h"
#include "pneumaid/ident/identify.h"
#include "pneumaid/model/parameters.h"

namespace pneumaid {

// One shard of N: the units whose name hashes (FNV-1a, 64 bit) to `index`
// modulo `count`. Stable across machines and runs.
struct Shard {
  int index = 0;
  int count = 1;
  bool Contains(const std::string& unit) const;
  // "i-of-N" for file names, empty for the whole fleet.
  std::string Suffix() const;
};

// The shard a cluster launcher gives this process: the Slurm array variables
// (index (SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN) / SLURM_ARRAY_TASK_STEP,
// count SLURM_ARRAY_TASK_COUNT), OMPI_COMM_WORLD_RANK / _SIZE, or PMI_RANK /
// PMI_SIZE, in that order. `getenv` is injected for tests. False (and `why`)
// when none is set or the values do not make a shard.
bool ShardFromEnvironment(const std::function<const char*(const char*)>& getenv, Shard* shard,
                          std::string* why);

struct BatchOptions {
  Parameters prior;          // identify's prior (what is not fitted)
  IdentifyOptions identify;  // tool_version and date also go into provenance
  bool refine = false;       // identify --refine with `spec`
  FitSpec spec;
  bool validate = false;  // validate the final set on the unit's validation runs
  bool diagnose = false;  // diagnose the final set with `diagnosis`
  // The diagnosis of each unit: one effect at most by default; `effects`
  // restricts the candidates, the thresholds are diagnose's own. `threads`
  // must stay 1 (the units run in parallel instead: `jobs`), and `stop` is
  // the unit's time limit, set by the batch. A given `log` is called from the
  // worker threads, one line at a time.
  DiagnoseOptions diagnosis = [] {
    DiagnoseOptions d;
    d.max_effects = 1;
    return d;
  }();
  int jobs = 1;  // worker threads; never more busy threads than this
  Shard shard;
  bool resume = false;  // skip units whose result is complete and up to date
  // A unit's work stops (cooperatively: the simulator and the refinement
  // check it) after this many seconds; 0: no limit.
  double timeout_per_unit_s = 0;
  // One line per unit done (and a progress line), for the CLI's stderr.
  std::function<void(const std::string&)> progress;

  bool IsValid(std::string* error) const;
};

struct UnitOutcome {
  std::string unit;
  enum class Status { kDone, kUpToDate, kFailed } status = Status::kFailed;
  std::string reason;   // failed: why
  std::string verdict;  // done: the fit's status (and validation, diagnose) in a few words
  double seconds = 0;
};

struct BatchSummary {
  std::vector<UnitOutcome> units;  // of this shard, by name
  // Subdirectories of the fleet without a unit.yaml, not run (a misnamed
  // manifest must not make a unit vanish unsaid).
  std::vector<std::string> not_units;
  int failed() const;
  std::string BriefReport() const;
};

// Runs the batch. Per unit it writes RESULTS/<unit>/ (params.yaml,
// report.txt, report.json, stamp.txt) as one directory rename, so a killed
// run leaves a complete result or none; then RESULTS/failures[.i-of-N].csv
// and RESULTS/summary[.i-of-N].csv. Throws InputError for a bad fleet
// directory or options only.
BatchSummary RunBatch(const std::string& fleet_dir, const std::string& results_dir,
                      const BatchOptions& options);

// `pneumaid merge`: the fleet summary of one or more results directories.
struct FleetParameter {
  std::string path;
  double median = 0, mad = 0;  // MAD scaled to sigma (x 1.4826)
  int units = 0;
};
struct FleetUnit {
  std::string unit, results_dir, verdict;
  std::map<std::string, double> values;           // params-v1 path -> value
  std::map<std::string, double> standard_errors;  // of those its fit determined
  // path -> robust z, |z| > the limit: (value - median) / hypot(MAD, its standard error)
  std::vector<std::pair<std::string, double>> outlying;
};
struct FleetFailure {
  std::string unit, reason, file;
};
struct FleetSummary {
  double outlier_z = 3.5;  // the limit the units were flagged with
  std::vector<FleetParameter> parameters;
  std::vector<FleetUnit> units;
  std::vector<FleetFailure> failures;
  std::string Csv() const;
  std::string Markdown() const;
};

// Reads every RESULTS/<unit>/params.yaml and summary and failure file.
// A parameter is compared across units only where at least 5 units have it
// and its spread is not zero. InputError when a directory is not a results
// directory.
FleetSummary MergeResults(const std::vector<std::string>& results_dirs, double outlier_z = 3.5);

}  // namespace pneumaid
