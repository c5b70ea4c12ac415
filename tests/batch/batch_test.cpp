// Fleet work on datasets/fleet (13 good units, one outlier with three times
// the static friction, one with a corrupt log): results per unit, failures
// recorded, the outlier flagged alone; shards disjoint and covering; the
// launchers' variables; resume; time limits; threads give what one thread does.
#include "pneumaid/batch/batch.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include "pneumaid/io/files.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"

namespace pneumaid {
namespace {

namespace fs = std::filesystem;
const std::string kFleet = std::string(PNEUMAID_SOURCE_DIR) + "/datasets/fleet";

fs::path Fresh(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("batch_" + name);
  fs::remove_all(dir);
  return dir;
}

BatchOptions Options(int jobs = 2) {
  BatchOptions options;
  options.prior = LoadParams(std::string(PNEUMAID_SOURCE_DIR) + "/configs/paper.yaml");
  options.identify.tool_version = "test";
  options.identify.date = "2026-01-01T00:00:00Z";
  options.jobs = jobs;
  return options;
}

std::string Read(const fs::path& path) { return ReadTextFile(path.string(), "a result"); }

TEST(BatchTest, AFleetGetsItsSetsItsFailureAndItsOutlier) {
  const fs::path results = Fresh("fleet");
  const BatchSummary summary = RunBatch(kFleet, results.string(), Options());
  ASSERT_EQ(summary.units.size(), 14u);
  EXPECT_EQ(summary.failed(), 1);
  for (const UnitOutcome& u : summary.units) {
    if (u.unit == "PVQ13-0014") {
      EXPECT_EQ(u.status, UnitOutcome::Status::kFailed);
      EXPECT_NE(u.reason.find("step-1.csv:1623: ragged row"), std::string::npos) << u.reason;
      EXPECT_FALSE(fs::exists(results / u.unit));
      continue;
    }
    EXPECT_EQ(u.status, UnitOutcome::Status::kDone) << u.unit << ": " << u.reason;
    for (const char* file : {"params.yaml", "report.txt", "report.json", "stamp.txt"})
      EXPECT_TRUE(fs::exists(results / u.unit / file)) << u.unit << " " << file;
  }
  EXPECT_NE(Read(results / "failures.csv").find("PVQ13-0014,"), std::string::npos);
  const FleetSummary fleet = MergeResults({results.string()});
  ASSERT_EQ(fleet.units.size(), 13u);
  ASSERT_EQ(fleet.failures.size(), 1u);
  EXPECT_EQ(fleet.failures[0].unit, "PVQ13-0014");
  for (const FleetUnit& u : fleet.units) {
    if (u.unit != "PVQ13-0013") {
      EXPECT_TRUE(u.outlying.empty()) << u.unit << " flagged for " << u.outlying.front().first;
      continue;
    }
    bool static_friction = false;
    for (const auto& [path, z] : u.outlying)
      static_friction = static_friction || path.find(".Fs") != std::string::npos;
    EXPECT_TRUE(static_friction) << "the outlier must be flagged for its static friction";
  }
  EXPECT_NE(fleet.Markdown().find("**PVQ13-0013**"), std::string::npos);
  const std::string table = fleet.Csv();
  EXPECT_NE(table.find("FAILED: "), std::string::npos);
  // The units' rows, then the failures', then the median and spread; every
  // value with every digit of its set (it was rounded to 6).
  EXPECT_LT(table.find("FAILED: "), table.find("\nmedian,"));
  const Parameters first = LoadParams((results / "PVQ13-0001" / "params.yaml").string());
  EXPECT_NE(table.find("," + FormatDouble(first.valve.increasing.q_max_kg_per_s) + ","),
            std::string::npos);
}

// A subdirectory without a unit.yaml (here a misnamed manifest) is not a
// unit: not run, and said so in the summary rather than dropped unsaid.
TEST(BatchTest, ASubdirectoryThatIsNoUnitIsSaidToBeSkipped) {
  const fs::path fleet = Fresh("not_units");
  fs::create_directories(fleet);
  fs::copy(kFleet + "/PVQ13-0001", fleet / "PVQ13-0001");
  fs::copy(kFleet + "/PVQ13-0002", fleet / "PVQ13-0002");
  fs::rename(fleet / "PVQ13-0002" / "unit.yaml", fleet / "PVQ13-0002" / "Unit.yml");
  fs::create_directories(fleet / ".git");     // hidden: not a word
  fs::create_directories(fleet / "results");  // the results kept in the fleet: neither
  BatchOptions options = Options(1);
  const BatchSummary summary = RunBatch(fleet.string(), (fleet / "results").string(), options);
  ASSERT_EQ(summary.units.size(), 1u);
  EXPECT_EQ(summary.units[0].unit, "PVQ13-0001");
  EXPECT_EQ(summary.not_units, std::vector<std::string>{(fleet / "PVQ13-0002").string()});
  EXPECT_NE(
      summary.BriefReport().find("skipped " + (fleet / "PVQ13-0002").string() + ": no unit.yaml"),
      std::string::npos)
      << summary.BriefReport();
}

TEST(BatchTest, ShardsAreDisjointAndCoverTheFleet) {
  std::vector<std::string> units;
  for (const auto& entry : fs::directory_iterator(kFleet)) {
    if (entry.is_directory()) units.push_back(entry.path().filename().string());
  }
  for (int count : {2, 3, 5}) {
    std::map<std::string, int> owners;
    for (int index = 0; index < count; ++index) {
      for (const std::string& u : units) owners[u] += Shard{index, count}.Contains(u);
    }
    for (const std::string& u : units) EXPECT_EQ(owners[u], 1) << u << " in " << count << " shards";
  }
  // Two shards into one results directory: their own failure files, and the
  // merge of the directory is the whole fleet.
  const fs::path results = Fresh("shards");
  int done = 0;
  for (int index = 0; index < 2; ++index) {
    BatchOptions options = Options(1);
    options.shard = {index, 2};
    for (const UnitOutcome& u : RunBatch(kFleet, results.string(), options).units)
      done += u.status == UnitOutcome::Status::kDone;
    EXPECT_TRUE(fs::exists(results / ("failures." + std::to_string(index) + "-of-2.csv")));
  }
  EXPECT_EQ(done, 13);
  EXPECT_EQ(MergeResults({results.string()}).units.size(), 13u);
  // The same directory twice is merged once; a unit with results in two
  // directories is refused (each counted twice in the median and spread).
  EXPECT_EQ(MergeResults({results.string(), (results / ".").string()}).units.size(), 13u);
  const fs::path copy = Fresh("shards_copy");
  fs::copy(results, copy, fs::copy_options::recursive);
  try {
    MergeResults({results.string(), copy.string()});
    ADD_FAILURE() << "a unit merged twice";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("has results here and in"), std::string::npos)
        << error.what();
  }
}

TEST(BatchTest, TheLaunchersVariablesGiveTheShard) {
  const auto from = [](std::map<std::string, std::string> env, Shard* shard, std::string* why) {
    return ShardFromEnvironment(
        [&env](const char* name) {
          const auto found = env.find(name);
          return found == env.end() ? nullptr : found->second.c_str();
        },
        shard, why);
  };
  Shard shard;
  std::string why;
  ASSERT_TRUE(from({{"SLURM_ARRAY_TASK_ID", "7"},
                    {"SLURM_ARRAY_TASK_MIN", "5"},
                    {"SLURM_ARRAY_TASK_STEP", "2"},
                    {"SLURM_ARRAY_TASK_COUNT", "4"}},
                   &shard, &why))
      << why;
  EXPECT_EQ(shard.index, 1);
  EXPECT_EQ(shard.count, 4);
  ASSERT_TRUE(from({{"OMPI_COMM_WORLD_RANK", "1"}, {"OMPI_COMM_WORLD_SIZE", "2"}}, &shard, &why));
  EXPECT_EQ(shard.index, 1);
  EXPECT_EQ(shard.count, 2);
  ASSERT_TRUE(from({{"PMI_RANK", "0"}, {"PMI_SIZE", "3"}}, &shard, &why));
  EXPECT_EQ(shard.count, 3);
  EXPECT_FALSE(from({}, &shard, &why));
  EXPECT_NE(why.find("SLURM_ARRAY_TASK_ID"), std::string::npos);
  EXPECT_FALSE(from({{"PMI_RANK", "3"}, {"PMI_SIZE", "3"}}, &shard, &why));
  EXPECT_FALSE(from({{"SLURM_ARRAY_TASK_ID", "6"},
                     {"SLURM_ARRAY_TASK_MIN", "5"},
                     {"SLURM_ARRAY_TASK_STEP", "2"},
                     {"SLURM_ARRAY_TASK_COUNT", "4"}},
                    &shard, &why));
}

TEST(BatchTest, ResumeSkipsWhatIsUpToDateAndRedoesWhatChanged) {
  const fs::path fleet = Fresh("resume_fleet");
  fs::create_directories(fleet);
  for (const char* unit : {"PVQ13-0001", "PVQ13-0002", "PVQ13-0003"})
    fs::copy(fs::path(kFleet) / unit, fleet / unit, fs::copy_options::recursive);
  const fs::path results = Fresh("resume_results");
  BatchOptions options = Options();
  std::map<std::string, std::string> verdicts;
  for (const UnitOutcome& u : RunBatch(fleet.string(), results.string(), options).units)
    verdicts[u.unit] = u.verdict;
  const std::string before = Read(results / "PVQ13-0001" / "params.yaml");
  options.resume = true;
  // Skipped, and the summary keeps each result's verdict (it said "up to
  // date" instead, and merge's fleet summary with it).
  for (const UnitOutcome& u : RunBatch(fleet.string(), results.string(), options).units) {
    EXPECT_EQ(u.status, UnitOutcome::Status::kUpToDate) << u.unit;
    EXPECT_EQ(u.verdict, verdicts[u.unit]) << u.unit;
    EXPECT_NE(u.verdict.find("identified"), std::string::npos) << u.verdict;
  }
  EXPECT_NE(Read(results / "summary.csv").find("PVQ13-0001,up to date,identified"),
            std::string::npos)
      << Read(results / "summary.csv");
  // A changed input (a re-exported manifest with a comment) is redone.
  std::ofstream(fleet / "PVQ13-0002" / "unit.yaml", std::ios::app) << "# re-exported\n";
  for (const UnitOutcome& u : RunBatch(fleet.string(), results.string(), options).units) {
    EXPECT_EQ(u.status,
              u.unit == "PVQ13-0002" ? UnitOutcome::Status::kDone : UnitOutcome::Status::kUpToDate)
        << u.unit;
  }
  // Other options are another result.
  options.identify.valve.fit_u_sat = false;
  for (const UnitOutcome& u : RunBatch(fleet.string(), results.string(), options).units)
    EXPECT_EQ(u.status, UnitOutcome::Status::kDone) << u.unit;
  EXPECT_NE(Read(results / "PVQ13-0001" / "params.yaml"), before);
}

TEST(BatchTest, ATimeLimitStopsAUnitsWorkAndRecordsWhy) {
  const fs::path fleet = Fresh("timeout_fleet");
  fs::create_directories(fleet);
  fs::copy(fs::path(kFleet) / "PVQ13-0001", fleet / "PVQ13-0001", fs::copy_options::recursive);
  BatchOptions options = Options(1);
  options.refine = true;
  options.spec = LoadFitSpec(std::string(PNEUMAID_SOURCE_DIR) + "/configs/fit-default.yaml");
  options.timeout_per_unit_s = 0.05;
  const BatchSummary summary = RunBatch(fleet.string(), Fresh("timeout").string(), options);
  ASSERT_EQ(summary.units.size(), 1u);
  EXPECT_EQ(summary.units[0].status, UnitOutcome::Status::kFailed);
  EXPECT_NE(summary.units[0].reason.find("time limit"), std::string::npos)
      << summary.units[0].reason;
  // (No bound on its seconds: identify alone takes longer than the limit
  // under the sanitizers; the reason shows that the stop flag ended it.)
}

// The concurrency test (also the ThreadSanitizer pass's): units identified on
// four threads give exactly what one thread gives.
TEST(BatchTest, ThreadsGiveWhatOneThreadGives) {
  const fs::path one = Fresh("one_thread"), four = Fresh("four_threads");
  RunBatch(kFleet, one.string(), Options(1));
  RunBatch(kFleet, four.string(), Options(4));
  for (const auto& entry : fs::directory_iterator(one)) {
    if (!entry.is_directory()) continue;
    EXPECT_EQ(Read(entry.path() / "params.yaml"),
              Read(four / entry.path().filename() / "params.yaml"))
        << entry.path().filename();
  }
}

// --validate and --diagnose per unit: a fleet of one validation-only unit
// whose rig has a valve lag (datasets/hidden/valve-lag).
TEST(BatchTest, ValidatesAndDiagnosesEachUnitWhenAsked) {
  const fs::path fleet = Fresh("diagnose_fleet");
  fs::create_directories(fleet);
  fs::copy(std::string(PNEUMAID_SOURCE_DIR) + "/datasets/hidden/valve-lag", fleet / "VL-0001",
           fs::copy_options::recursive);
  BatchOptions options = Options(1);
  options.validate = true;
  options.diagnose = true;
  // Two candidates: the batch's plumbing, not diagnose's choice among all
  // (diagnose_test.cpp).
  options.diagnosis.effects = {"flow_sensor_lag", "valve_lag"};
  const fs::path results = Fresh("diagnose_results");
  const BatchSummary summary = RunBatch(fleet.string(), results.string(), options);
  ASSERT_EQ(summary.units.size(), 1u);
  ASSERT_EQ(summary.units[0].status, UnitOutcome::Status::kDone) << summary.units[0].reason;
  EXPECT_NE(summary.units[0].verdict.find("validation"), std::string::npos);
  EXPECT_NE(summary.units[0].verdict.find("diagnose: valve_lag"), std::string::npos)
      << summary.units[0].verdict;
  const std::string json = Read(results / "VL-0001" / "report.json");
  EXPECT_NE(json.find("\"named_effects\": [\"valve_lag\"]"), std::string::npos);
  EXPECT_NE(json.find("\"validation\": {\"format\": \"pneumaid-report/1\""), std::string::npos);
  // The candidates asked for, and no other, were fitted.
  EXPECT_NE(json.find("\"flow_sensor_lag\""), std::string::npos);
  EXPECT_EQ(json.find("\"cross_leakage\""), std::string::npos);
  // The same options: up to date. Other candidates or another decision
  // rule: another result, redone (and here stopped by a time limit once its
  // identify is done, which does not check it, to keep the test short).
  options.resume = true;
  EXPECT_EQ(RunBatch(fleet.string(), results.string(), options).units[0].status,
            UnitOutcome::Status::kUpToDate);
  options.timeout_per_unit_s = 1e-3;
  const auto redone = [&](const char* what) {
    const UnitOutcome outcome = RunBatch(fleet.string(), results.string(), options).units[0];
    EXPECT_EQ(outcome.status, UnitOutcome::Status::kFailed) << what;
    EXPECT_NE(outcome.reason.find("time limit"), std::string::npos) << what << outcome.reason;
  };
  options.diagnosis.effects = {"valve_lag"};
  redone("candidates");
  options.diagnosis.effects = {"flow_sensor_lag", "valve_lag"};
  options.diagnosis.min_held_back_gain = 0.2;
  redone("decision rule");
}

TEST(BatchTest, BadFleetsAndOptionsAreInputErrors) {
  EXPECT_THROW(RunBatch("/nonexistent/fleet", Fresh("bad").string(), Options()), InputError);
  const fs::path empty = Fresh("empty_fleet");
  fs::create_directories(empty);
  EXPECT_THROW(RunBatch(empty.string(), Fresh("bad").string(), Options()), InputError);
  BatchOptions options = Options();
  options.shard = {2, 2};
  std::string error;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("shard"), std::string::npos);
  // The diagnosis's options are checked before any unit, by their names.
  options = Options();
  options.diagnose = true;
  options.diagnosis.effects = {"warp_drive"};
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("diagnosis.effects: unknown effect 'warp_drive'"), std::string::npos)
      << error;
  const fs::path not_written = Fresh("bad_diagnosis");
  EXPECT_THROW(RunBatch(kFleet, not_written.string(), options), InputError);
  EXPECT_FALSE(fs::exists(not_written));
  options.diagnosis.effects = {"pipeline_lag"};  // the paper's prior has a tube lag
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("diagnosis.effects: 'pipeline_lag' is already in the prior"),
            std::string::npos)
      << error;
  options.diagnosis.effects.clear();
  options.diagnosis.threads = 2;
  EXPECT_FALSE(options.IsValid(&error));
  EXPECT_NE(error.find("diagnosis.threads"), std::string::npos) << error;
  options.diagnose = false;  // not asked for: not checked
  EXPECT_TRUE(options.IsValid(&error)) << error;
  EXPECT_THROW(MergeResults({empty.string()}), InputError);
  // Results written into the fleet directory would replace each unit's
  // directory, logs and all: refused before any unit runs, the logs intact.
  const fs::path fleet = Fresh("results_in_fleet");
  fs::create_directories(fleet);
  fs::copy(fs::path(kFleet) / "PVQ13-0001", fleet / "PVQ13-0001", fs::copy_options::recursive);
  const auto logs = std::distance(fs::directory_iterator(fleet / "PVQ13-0001"), {});
  try {
    RunBatch(fleet.string(), fleet.string(), Options());
    ADD_FAILURE() << "results written over the fleet's units";
  } catch (const InputError& error) {
    EXPECT_NE(
        std::string(error.what()).find("holds a unit (unit.yaml), not an earlier batch result"),
        std::string::npos)
        << error.what();
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(fleet / "PVQ13-0001"), {}), logs);
  EXPECT_TRUE(fs::exists(fleet / "PVQ13-0001" / "unit.yaml"));
}

}  // namespace
}  // namespace pneumaid
