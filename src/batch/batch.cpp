#include "pneumaid/batch/batch.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <locale>
#include <mutex>
#include <sstream>
#include <thread>

#include "pneumaid/ident/refine.h"
#include "pneumaid/io/files.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/json.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/io/sha256.h"
#include "pneumaid/validate/validate.h"

// The batch: units in worker threads, each unit's result written as one
// directory rename, a monitor that raises a unit's stop flag at its time
// limit, the shard's failure and summary files at the end.
namespace pneumaid {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

// What a unit's result depends on besides its own files: the tool, the
// prior, the steps asked for and the refinement spec.
std::string OptionsFingerprint(const BatchOptions& o) {
  std::ostringstream text;
  text.imbue(std::locale::classic());
  text << "tool " << o.identify.tool_version << "\nprior " << Sha256Hex(ParamsToYaml(o.prior))
       << "\ncomponents";
  for (Component c : o.identify.components) text << " " << ToString(c);
  // The spec's contents, not its path: an edited spec is another result.
  std::string spec_text = o.spec.source;
  std::error_code error;
  if (o.refine && fs::is_regular_file(o.spec.source, error))
    spec_text = Sha256Hex(ReadTextFile(o.spec.source, "the fit spec"));
  text << "\nfit_u_sat " << o.identify.valve.fit_u_sat << "\nrefine " << o.refine << " "
       << spec_text << "\nvalidate " << o.validate << "\ndiagnose " << o.diagnose << "\n";
  if (o.diagnose) {
    // Whatever changes a diagnosis (candidates, iterations, decision rule,
    // windows), not how it is run (threads, stop, log).
    const DiagnoseOptions& d = o.diagnosis;
    text << "diagnosis " << d.max_effects << " " << d.max_iterations << " " << std::hexfloat
         << d.min_held_back_gain << " " << d.min_improved_share << " " << d.min_signature_share
         << " " << d.min_gap_over_noise << " " << d.window_s << " " << d.worst_windows << " "
         << d.after_change_s << std::defaultfloat << " effects";
    for (const std::string& effect : d.effects) text << " " << effect;
    text << "\n";
  }
  return text.str();
}

// The stamp of a unit's result: the options' fingerprint and the SHA-256 of
// every file of the unit directory, by name. A log the read parsed gives the
// hash of the very bytes it parsed (its Experiment::sha256, the provenance's),
// so the stamp, the provenance and the fit agree even if a file changes
// while the batch runs, and no log is hashed twice.
std::string Stamp(const fs::path& unit_dir, const std::string& fingerprint, const Unit& unit) {
  std::map<std::string, std::string> parsed;
  for (const Experiment& e : unit.experiments) {
    if (fs::path(e.entry.file).parent_path().empty()) parsed[e.entry.file] = e.sha256;
  }
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(unit_dir)) {
    if (entry.is_regular_file()) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  std::string stamp = fingerprint;
  for (const fs::path& file : files) {
    const std::string name = file.filename().string();
    const auto known = parsed.find(name);
    stamp += name + " " +
             (known != parsed.end() ? known->second
                                    : Sha256Hex(ReadTextFile(file.string(), "a unit file"))) +
             "\n";
  }
  return stamp;
}

bool UpToDate(const fs::path& result_dir, const std::string& stamp) {
  const fs::path stamp_file = result_dir / "stamp.txt";
  if (!fs::exists(stamp_file) || !fs::exists(result_dir / "params.yaml")) return false;
  return ReadTextFile(stamp_file.string(), "a stamp") == stamp;
}

// The verdict an up-to-date result was written with (its report.json), so
// that a resumed run's summary keeps it; empty when it cannot be read.
std::string EarlierVerdict(const fs::path& result_dir) {
  try {
    const YAML::Node json = YAML::LoadFile((result_dir / "report.json").string());
    if (json["verdict"] && json["verdict"].IsScalar()) return json["verdict"].as<std::string>();
  } catch (const YAML::Exception&) {
  }
  return "";
}

// One unit, start to finish; throws on failure (InputError, FitError, ...).
UnitOutcome ProcessUnit(const std::string& name, const fs::path& unit_dir,
                        const fs::path& results_dir, const BatchOptions& options,
                        const std::string& fingerprint, const std::atomic<bool>* stop) {
  UnitOutcome outcome;
  outcome.unit = name;
  // A worker is one busy thread: the read hashes each log on it (no second
  // thread), and the stamp takes those hashes.
  ReadOptions read;
  read.hash_on_second_thread = false;
  const Unit unit = ReadUnit(unit_dir.string(), read);
  const std::string stamp = Stamp(unit_dir, fingerprint, unit);
  if (options.resume && UpToDate(results_dir / name, stamp)) {
    outcome.status = UnitOutcome::Status::kUpToDate;
    outcome.verdict = EarlierVerdict(results_dir / name);
    if (outcome.verdict.empty()) outcome.verdict = "up to date";
    return outcome;
  }
  RefineOptions refine = RefineOptions::ForIdentify();
  refine.simulation.stop = stop;
  refine.validation.stop = stop;
  if (options.refine) CheckRefinable(options.prior, unit, options.spec, refine);
  std::ostringstream report;
  std::ostringstream json;
  IdentifyReport identified;
  Parameters params = Identify(unit, options.prior, options.identify, &identified);
  report << identified.BriefReport();
  json << "{\"format\": \"pneumaid-batch-unit/1\", \"unit\": " << JsonString(name)
       << ", \"directory\": " << JsonString(unit_dir.string());
  std::string verdict = "identified";
  for (const std::string& fit : identified.NotAccepted()) verdict += "; " + fit;
  if (options.refine) {
    const RefineResult r = Refine(params, unit, options.spec, refine);
    report << r.BriefReport();
    if (!r.has_values()) throw FitError("refinement of unit " + name, r.reason);
    if (stop != nullptr && stop->load()) throw FitError("unit " + name, "time limit reached");
    params = r.params;
    verdict = std::string("refine: ") + ToString(r.status);
    if (r.start_written) verdict += " (the component fits written)";
    json << ", \"refine\": {\"status\": " << JsonString(ToString(r.status))
         << ", \"reduced_chi_square\": " << JsonNumber(r.reduced_chi_square)
         << ", \"start_written\": " << (r.start_written ? "true" : "false") << "}";
  }
  if (options.validate) {
    ValidationOptions v;
    v.simulation.stop = stop;
    const ValidationReport validation = ValidateUnit(params, unit, v);
    if (validation.numerical_failure()) {
      throw FitError("validation of unit " + name, "a simulation failed");
    }
    report << validation.BriefReport();
    verdict += validation.thresholds_met() ? "; validation met" : "; validation missed";
    json << ", \"validation\": " << ReportToJson(validation);
  }
  if (options.diagnose) {
    DiagnoseOptions d = options.diagnosis;
    d.stop = stop;
    // A candidate asked for that this unit's set has gained since the prior
    // (refine's creep fit adds stick_creep) is not tried; with none left, the
    // diagnosis maps the discrepancy alone.
    const std::vector<std::string> gained = PresentEffects(d.effects, params);
    for (const std::string& effect : gained)
      d.effects.erase(std::find(d.effects.begin(), d.effects.end(), effect));
    if (!gained.empty() && d.effects.empty()) d.max_effects = 0;
    std::string not_tried;
    for (const std::string& effect : gained) not_tried += (not_tried.empty() ? "" : ", ") + effect;
    if (!not_tried.empty())
      not_tried = " (not tried, already in the unit's set: " + not_tried + ")";
    const DiagnoseResult diagnosis = Diagnose(params, unit, d);
    if (diagnosis.before.numerical_failure() || (stop != nullptr && stop->load())) {
      throw FitError("diagnose of unit " + name, "a simulation failed or the time limit passed");
    }
    report << diagnosis.BriefReport();
    verdict += "; diagnose: ";
    if (diagnosis.named_effects.empty()) verdict += "none named";
    for (std::size_t k = 0; k < diagnosis.named_effects.size(); ++k)
      verdict += (k > 0 ? ", " : "") + diagnosis.named_effects[k];
    verdict += not_tried;
    json << ", \"diagnose\": " << DiagnoseToJson(diagnosis);
  }
  json << ", \"verdict\": " << JsonString(verdict) << "}\n";
  ReplaceDirectoryAtomically((results_dir / name).string(),
                             {{"params.yaml", ParamsToYaml(params)},
                              {"report.txt", report.str()},
                              {"report.json", json.str()},
                              {"stamp.txt", stamp}});  // last in the check, first to be trusted
  outcome.status = UnitOutcome::Status::kDone;
  outcome.verdict = verdict;
  return outcome;
}

const char* StatusName(UnitOutcome::Status status) {
  switch (status) {
    case UnitOutcome::Status::kDone:
      return "done";
    case UnitOutcome::Status::kUpToDate:
      return "up to date";
    case UnitOutcome::Status::kFailed:
      return "failed";
  }
  return "?";
}

}  // namespace

bool Shard::Contains(const std::string& unit) const {
  std::uint64_t hash = 1469598103934665603ull;  // FNV-1a 64
  for (unsigned char c : unit) {
    hash ^= c;
    hash *= 1099511628211ull;
  }
  return static_cast<int>(hash % static_cast<std::uint64_t>(count)) == index;
}

std::string Shard::Suffix() const {
  return count == 1 ? "" : "." + std::to_string(index) + "-of-" + std::to_string(count);
}

bool ShardFromEnvironment(const std::function<const char*(const char*)>& getenv, Shard* shard,
                          std::string* why) {
  const auto number = [&getenv](const char* name, long* value) {
    const char* text = getenv(name);
    if (text == nullptr || *text == '\0') return false;
    char* end = nullptr;
    *value = std::strtol(text, &end, 10);  // integers: no locale involved
    return *end == '\0';
  };
  long id = 0, min = 0, step = 1, count = 0, rank = 0, size = 0;
  if (number("SLURM_ARRAY_TASK_ID", &id) && number("SLURM_ARRAY_TASK_COUNT", &count)) {
    if (!number("SLURM_ARRAY_TASK_MIN", &min)) min = 0;
    if (!number("SLURM_ARRAY_TASK_STEP", &step)) step = 1;
    if (step <= 0 || (id - min) % step != 0) {
      *why = "SLURM_ARRAY_TASK_ID, _MIN and _STEP do not give a whole index";
      return false;
    }
    rank = (id - min) / step;
    size = count;
  } else if (number("OMPI_COMM_WORLD_RANK", &rank) && number("OMPI_COMM_WORLD_SIZE", &size)) {
  } else if (number("PMI_RANK", &rank) && number("PMI_SIZE", &size)) {
  } else {
    *why =
        "no Slurm array (SLURM_ARRAY_TASK_ID, SLURM_ARRAY_TASK_COUNT), Open MPI "
        "(OMPI_COMM_WORLD_RANK, OMPI_COMM_WORLD_SIZE) or PMI (PMI_RANK, PMI_SIZE) variables set";
    return false;
  }
  if (size < 1 || rank < 0 || rank >= size) {
    *why = "the launcher's index " + std::to_string(rank) + " is not in 0.." +
           std::to_string(size - 1);
    return false;
  }
  shard->index = static_cast<int>(rank);
  shard->count = static_cast<int>(size);
  return true;
}

bool BatchOptions::IsValid(std::string* error) const {
  const auto fail = [error](const std::string& what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (jobs < 1) return fail("jobs must be >= 1");
  if (shard.count < 1 || shard.index < 0 || shard.index >= shard.count)
    return fail("shard: expected 0 <= index < count");
  if (!(timeout_per_unit_s >= 0)) return fail("timeout_per_unit_s must be >= 0");
  if (!identify.IsValid(error)) return false;
  if (refine && !spec.IsValid(error)) return false;
  if (diagnose) {
    std::string why;
    if (!diagnosis.IsValid(&why)) return fail("diagnosis." + why);
    // identify keeps the prior's effects (and its tube lag): a candidate
    // there would fail every unit after its fits.
    if (!EffectsAbsent(diagnosis.effects, prior, "prior", &why)) return fail("diagnosis." + why);
    if (diagnosis.threads != 1)
      return fail("diagnosis.threads must be 1 (a batch runs its units in parallel: jobs)");
  }
  return true;
}

int BatchSummary::failed() const {
  return static_cast<int>(std::count_if(units.begin(), units.end(), [](const UnitOutcome& u) {
    return u.status == UnitOutcome::Status::kFailed;
  }));
}

std::string BatchSummary::BriefReport() const {
  std::ostringstream out;
  int up_to_date = 0;
  for (const UnitOutcome& u : units) up_to_date += u.status == UnitOutcome::Status::kUpToDate;
  out << "Batch: " << units.size() << " units, " << failed() << " failed, " << up_to_date
      << " up to date\n";
  for (const UnitOutcome& u : units) {
    char seconds[32];
    std::snprintf(seconds, sizeof(seconds), "%.1f s", u.seconds);
    out << "  " << u.unit << ": " << StatusName(u.status) << " ("
        << (u.status == UnitOutcome::Status::kFailed ? u.reason : u.verdict) << ", " << seconds
        << ")\n";
  }
  for (const std::string& path : not_units) out << "  skipped " << path << ": no unit.yaml\n";
  return out.str();
}

BatchSummary RunBatch(const std::string& fleet_dir, const std::string& results_dir,
                      const BatchOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw InputError("batch options", 0, 0, error);
  // A unit is keyed by its directory's name: a corrupt manifest has no id
  // to trust.
  std::vector<std::string> not_units;
  const std::vector<std::string> fleet = FleetUnits(fleet_dir, &not_units);
  not_units.erase(std::remove_if(not_units.begin(), not_units.end(),
                                 [&](const std::string& path) {
                                   std::error_code ignored;  // results kept in the fleet
                                   return fs::equivalent(path, results_dir, ignored);
                                 }),
                  not_units.end());
  if (fleet.empty()) {
    std::string others;
    for (const std::string& path : not_units)
      others += (others.empty() ? "; without one: " : ", ") + fs::path(path).filename().string();
    throw InputError(
        fleet_dir, 0, 0,
        "no unit directories (subdirectories holding a unit.yaml) in the fleet" + others);
  }
  std::vector<std::string> units;
  for (const std::string& path : fleet) {
    const std::string unit = fs::path(path).filename().string();
    if (options.shard.Contains(unit)) units.push_back(unit);
  }
  // Each unit's results replace the directory results/<unit> whole: it must
  // not hold a unit (results in the fleet directory itself would delete
  // every unit's logs).
  for (const std::string& unit : units) {
    const fs::path target = fs::path(results_dir) / unit;
    std::error_code error;
    if (fs::exists(target / "unit.yaml", error) ||
        fs::equivalent(target, fs::path(fleet_dir) / unit, error)) {
      throw InputError(results_dir, 0, 0,
                       "results directory: '" + target.string() +
                           "' holds a unit (unit.yaml), not an earlier batch result; batch "
                           "replaces it whole, so it must not be the fleet directory");
    }
  }
  std::error_code created;
  fs::create_directories(results_dir, created);
  if (created) throw InputError(results_dir, 0, 0, "cannot create: " + created.message());
  const std::string fingerprint = OptionsFingerprint(options);
  BatchSummary summary;
  summary.not_units = not_units;
  summary.units.resize(units.size());
  // One stop flag per unit (a late store by the monitor can only hit the unit
  // it was meant for), one deadline and current unit per worker.
  const int workers = std::max(1, std::min<int>(options.jobs, static_cast<int>(units.size())));
  std::vector<std::atomic<bool>> stop(units.size());
  for (auto& flag : stop) flag = false;
  std::vector<std::atomic<long long>> deadline(static_cast<std::size_t>(workers));
  std::vector<std::atomic<std::size_t>> current(static_cast<std::size_t>(workers));
  for (auto& d : deadline) d = 0;
  // Beyond a year is no limit (and no overflow of the clock's count).
  const bool limited = options.timeout_per_unit_s > 0 && options.timeout_per_unit_s < 3.2e7;
  std::atomic<bool> finished{false};
  std::atomic<std::size_t> next{0}, done{0};
  std::mutex progress_mutex;
  // A diagnose log of the caller's is called from every worker, one line at
  // a time.
  std::mutex diagnosis_log_mutex;
  BatchOptions unit_options = options;
  if (options.diagnosis.log) {
    unit_options.diagnosis.log = [&options, &diagnosis_log_mutex](const std::string& line) {
      std::lock_guard<std::mutex> lock(diagnosis_log_mutex);
      options.diagnosis.log(line);
    };
  }
  const auto started = Clock::now();
  const auto worker = [&](int w) {
    for (std::size_t i = next++; i < units.size(); i = next++) {
      UnitOutcome& outcome = summary.units[i];
      const auto unit_start = Clock::now();
      current[w] = i;
      if (limited) {
        deadline[w] = (unit_start + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(options.timeout_per_unit_s)))
                          .time_since_epoch()
                          .count();
      }
      try {
        outcome = ProcessUnit(units[i], fs::path(fleet_dir) / units[i], results_dir, unit_options,
                              fingerprint, &stop[i]);
      } catch (const std::exception& failure) {
        outcome = UnitOutcome{};
        outcome.unit = units[i];
        outcome.status = UnitOutcome::Status::kFailed;
        outcome.reason = stop[i]
                             ? "time limit of " + FormatSignificant(options.timeout_per_unit_s, 6) +
                                   " s reached (" + failure.what() + ")"
                             : failure.what();
      }
      deadline[w] = 0;
      outcome.seconds = std::chrono::duration<double>(Clock::now() - unit_start).count();
      const std::size_t count = ++done;
      if (options.progress) {
        const double elapsed = std::chrono::duration<double>(Clock::now() - started).count();
        const double eta = elapsed / count * (units.size() - count);
        char line[400];
        std::snprintf(line, sizeof(line), "[%zu/%zu, %.0f s left] %s: %s", count, units.size(), eta,
                      outcome.unit.c_str(),
                      outcome.status == UnitOutcome::Status::kFailed
                          ? ("FAILED: " + outcome.reason).c_str()
                          : outcome.verdict.c_str());
        std::lock_guard<std::mutex> lock(progress_mutex);
        options.progress(line);
      }
    }
  };
  std::thread monitor([&] {
    while (!finished) {
      const long long now = Clock::now().time_since_epoch().count();
      for (int w = 0; w < workers; ++w) {
        const long long d = deadline[w];
        if (d != 0 && now > d) stop[current[w]] = true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  std::vector<std::thread> pool;
  for (int w = 1; w < workers; ++w) pool.emplace_back(worker, w);
  worker(0);
  for (std::thread& t : pool) t.join();
  finished = true;
  monitor.join();
  // The shard's own files: failures and the per-unit summary.
  std::ostringstream failures, table;
  failures << "unit,reason\n";
  table << "unit,status,verdict,seconds\n";
  for (const UnitOutcome& u : summary.units) {
    if (u.status == UnitOutcome::Status::kFailed)
      failures << CsvField(u.unit) << "," << CsvField(u.reason) << "\n";
    table << CsvField(u.unit) << "," << StatusName(u.status) << ","
          << CsvField(u.status == UnitOutcome::Status::kFailed ? u.reason : u.verdict) << ","
          << FormatSignificant(u.seconds, 4) << "\n";
  }
  const std::string suffix = options.shard.Suffix();
  WriteFileAtomically((fs::path(results_dir) / ("failures" + suffix + ".csv")).string(),
                      failures.str());
  WriteFileAtomically((fs::path(results_dir) / ("summary" + suffix + ".csv")).string(),
                      table.str());
  return summary;
}

}  // namespace pneumaid
