// The rig-data reader: one malformed input per error class of the format's
// Errors section, inputs that must be accepted, and conversion to SI.
#include "pneumaid/io/rig_data.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <map>

#include "pneumaid/io/files.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/rig_writer.h"
#include "pneumaid/io/sha256.h"

namespace pneumaid {
namespace {

namespace fs = std::filesystem;

const char* kManifest = R"(format: pneumaid-rig/1
unit: TEST-1
rig:
  supply_pressure: "5 bar"
  cylinder: {bore: "16 mm", rod: "6 mm", stroke: "50 mm"}
  orientation: horizontal
  position_origin: retracted
sensors:
  q: {tau: 0.03, sigma: 2.0e-7}
experiments:
  - {id: valve-1, kind: valve, file: valve.csv}
  - {id: pipe-38, kind: pipeline, file: pipe.csv, tube_length: "38 cm"}
  - {id: step-1, kind: validation, file: step.csv}
)";

const char* kValve =
    "t [s],u [V],p_up [bar_g],p_down [bar_g],q [l/min]\n"
    "0,0,4,0,0\n0.001,0.5,4,0,3\n0.002,1,4,0,4.7\n";
const char* kPipe = "t [ms],u,q_in [l/min],q_out [g/s]\n0,0,0,0\n1,1,4.7,0.05\n2,1,4.7,0.09\n";
const char* kStep =
    "t [s],u [V],x [mm],p1 [bar],p2 [kPa],q1 [kg/s],q2 [kg/s],temp [degC]\n"
    "0,1,0,1,100,0,0,20\n0.001,1,0.5,1.5,100,1e-5,-1e-6,20\n"
    "0.002,1,50,2,110,2e-5,-2e-6,21\n";

class RigDataTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("pneumaid_rig_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "unit");
    files_ = {
        {"unit.yaml", kManifest}, {"valve.csv", kValve}, {"pipe.csv", kPipe}, {"step.csv", kStep}};
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string UnitDir() const { return (dir_ / "unit").string(); }

  void WriteAll() {
    for (const auto& [name, text] : files_)
      std::ofstream(dir_ / "unit" / name, std::ios::binary) << text;
  }

  std::set<std::string> Listing() const {
    std::set<std::string> names;
    for (const auto& entry : fs::recursive_directory_iterator(dir_))
      names.insert(entry.path().string());
    return names;
  }

  fs::path dir_;
  std::map<std::string, std::string> files_;
};

TEST_F(RigDataTest, ReadsAValidUnitIntoSI) {
  WriteAll();
  const Unit unit = ReadUnit(UnitDir());
  EXPECT_EQ(unit.manifest.unit, "TEST-1");
  ASSERT_EQ(unit.experiments.size(), 3u);
  const RigConstants& rig = unit.manifest.rig;
  EXPECT_NEAR(rig.area_1_m2(), 2.0106e-4, 1e-8);
  EXPECT_NEAR(rig.area_2_m2(), 1.7279e-4, 1e-8);
  EXPECT_DOUBLE_EQ(rig.supply_pressure_Pa, 5e5);
  // Defaults are reported, by path.
  const auto& defaults = unit.manifest.defaults_used;
  EXPECT_NE(std::find(defaults.begin(), defaults.end(), "rig.atmospheric_pressure"),
            defaults.end());
  EXPECT_NE(std::find(defaults.begin(), defaults.end(), "rig.cylinder.dead_volume_1"),
            defaults.end());
  EXPECT_EQ(std::find(defaults.begin(), defaults.end(), "rig.cylinder.bore"), defaults.end());
  // Sensors: flow sigma given as volumetric m3/s, stored as mass flow.
  EXPECT_NEAR(*unit.manifest.sensors.at("q").sigma, 2.0e-7 * 1.178, 1e-15);

  const Experiment& valve = unit.experiments[0];
  EXPECT_DOUBLE_EQ(valve.column("p_up")[0], 4e5 + 1e5);           // gauge + atmosphere
  EXPECT_NEAR(valve.column("q")[2], 4.7e-3 / 60 * 1.178, 1e-15);  // l/min -> kg/s
  EXPECT_EQ(valve.sha256.size(), 64u);
  const Experiment& pipe = unit.experiments[1];
  EXPECT_DOUBLE_EQ(pipe.column("t")[2], 0.002);     // ms
  EXPECT_DOUBLE_EQ(pipe.column("q_out")[1], 5e-5);  // g/s: mass flow as it stands
  EXPECT_DOUBLE_EQ(*pipe.entry.tube_length_m, 0.38);
  const Experiment& step = unit.experiments[2];
  EXPECT_DOUBLE_EQ(step.column("x")[0], -0.025);  // retracted origin -> mid
  EXPECT_DOUBLE_EQ(step.column("x")[2], 0.025);
  EXPECT_DOUBLE_EQ(step.column("p1")[1], 1.5e5);
  EXPECT_DOUBLE_EQ(step.column("p2")[2], 1.1e5);
  EXPECT_EQ(step.ignored_columns, std::vector<std::string>{"temp"});
  const Trajectory run = step.AsTrajectory();
  EXPECT_EQ(run.size(), 3u);
  EXPECT_TRUE(run.v_m_per_s.empty());
  EXPECT_DOUBLE_EQ(run.q2_kg_per_s[2], -2e-6);
}

// A logger's absolute clock (Unix time): time counts from the log's first
// sample, the logged origin is kept, the intervals are the logged ones (to
// the 2.4e-7 s a double resolves at 1.7e9 s).
TEST_F(RigDataTest, TimeCountsFromTheLogsFirstSample) {
  files_["step.csv"] =
      "t [s],u [V],x [mm],p1 [bar],p2 [kPa]\n"
      "1732500000.0,1,0,1,100\n1732500000.001,1,0.5,1.5,100\n1732500000.002,1,1,2,110\n";
  WriteAll();
  const Unit unit = ReadUnit(UnitDir());
  const Experiment& step = unit.experiments[2];
  EXPECT_EQ(step.time_origin_s, 1732500000.0);
  EXPECT_EQ(step.column("t")[0], 0.0);
  EXPECT_NEAR(step.column("t")[1], 0.001, 3e-7);
  EXPECT_NEAR(step.column("t")[2], 0.002, 3e-7);
  EXPECT_EQ(unit.experiments[1].column("t")[0], 0.0);  // a log that starts at 0 is unchanged
  EXPECT_EQ(unit.experiments[1].time_origin_s, 0.0);
}

// Each log's SHA-256 is its bytes' whether hashed on a second thread or on
// the reading one (a batch worker's).
TEST_F(RigDataTest, HashesEachLogOnceWhereverItIsHashed) {
  WriteAll();
  const Unit threaded = ReadUnit(UnitDir());
  ReadOptions here;
  here.hash_on_second_thread = false;
  const Unit inline_hashed = ReadUnit(UnitDir(), here);
  ASSERT_EQ(threaded.experiments.size(), inline_hashed.experiments.size());
  for (std::size_t i = 0; i < threaded.experiments.size(); ++i) {
    const Experiment& e = threaded.experiments[i];
    EXPECT_EQ(e.sha256, Sha256Hex(ReadTextFile(e.path, "log")));
    EXPECT_EQ(inline_hashed.experiments[i].sha256, e.sha256);
  }
}

TEST_F(RigDataTest, AcceptsBomCrlfCommentsAndBlankLines) {
  std::string crlf;
  for (char c : std::string("# logged by rig 4\n\n") + kStep) {
    if (c == '\n') crlf += '\r';
    crlf += c;
  }
  files_["step.csv"] = "\xEF\xBB\xBF" + crlf;
  WriteAll();
  const Unit unit = ReadUnit(UnitDir());
  EXPECT_DOUBLE_EQ(unit.experiments[2].column("p1")[2], 2e5);
}

struct BadUnit {
  const char* name;
  const char* file;  // which file to change
  const char* find;  // text to replace ("" = replace the whole file)
  const char* replace;
  const char* where;    // expected "file:line" prefix of the message (file relative to the unit)
  const char* message;  // a part of the message
};

class RigDataBadInputTest : public RigDataTest, public ::testing::WithParamInterface<BadUnit> {};

TEST_P(RigDataBadInputTest, OneMessageNamingFileLineAndExpectation) {
  const BadUnit& c = GetParam();
  std::string& text = files_[c.file];
  if (std::string(c.find).empty()) {
    text = c.replace;
  } else {
    const auto at = text.find(c.find);
    ASSERT_NE(at, std::string::npos) << c.find;
    text.replace(at, std::string(c.find).size(), c.replace);
  }
  WriteAll();
  const auto before = Listing();
  try {
    ReadUnit(UnitDir());
    FAIL() << "accepted " << c.name;
  } catch (const InputError& error) {
    const std::string expected = (dir_ / "unit" / c.where).string();
    EXPECT_EQ(std::string(error.what()).rfind(expected, 0), 0u) << error.what();
    EXPECT_NE(std::string(error.what()).find(c.message), std::string::npos) << error.what();
  }
  EXPECT_EQ(Listing(), before);  // nothing written
}

INSTANTIATE_TEST_SUITE_P(
    ErrorClasses, RigDataBadInputTest,
    ::testing::Values(
        BadUnit{"missing_key", "unit.yaml", "unit: TEST-1\n", "", "unit.yaml:1",
                "missing required key 'unit'"},
        BadUnit{"unknown_key", "unit.yaml", "{bore:", "{bor:", "unit.yaml:5:",
                "unknown key 'rig.cylinder.bor' (expected bore, dead_volume_1, dead_volume_2, rod, "
                "stroke)"},
        BadUnit{"duplicate_key", "unit.yaml", "stroke: \"50 mm\"}",
                "stroke: \"50 mm\", stroke: \"45 mm\"}", "unit.yaml:5:", "duplicate key 'stroke'"},
        // A key with nothing after it: its own line, not the next key's.
        BadUnit{"empty_sensors", "unit.yaml", "sensors:\n  q: {tau: 0.03, sigma: 2.0e-7}\n",
                "sensors:\n", "unit.yaml:8:", "sensors: expected a value after the key"},
        BadUnit{"empty_rig_key", "unit.yaml", "  orientation: horizontal\n", "  orientation:\n",
                "unit.yaml:6:", "rig.orientation: expected a value after"},
        BadUnit{"wrong_format", "unit.yaml", "pneumaid-rig/1", "pneumaid-rig/2",
                "unit.yaml:1:", "expected format: pneumaid-rig/1"},
        BadUnit{"missing_file", "unit.yaml", "file: pipe.csv", "file: pipe2.csv", "unit.yaml:12",
                "'pipe2.csv' not found"},
        BadUnit{"missing_column", "valve.csv", "p_down [bar_g]", "p_dn [bar_g]", "valve.csv:1",
                "missing column 'p_down'"},
        BadUnit{"ragged_row", "valve.csv", "0.001,0.5,4,0,3", "0.001,0.5,4,0", "valve.csv:3",
                "ragged row"},
        BadUnit{"non_numeric", "valve.csv", "0.001,0.5,4,0,3", "0.001,0.5,four,0,3",
                "valve.csv:3:3", "expected a finite number"},
        BadUnit{"non_finite", "valve.csv", "0.001,0.5,4,0,3", "0.001,0.5,inf,0,3", "valve.csv:3:3",
                "expected a finite number"},
        BadUnit{"non_increasing_time", "valve.csv", "0.002,1,4", "0.001,1,4", "valve.csv:4:1",
                "strictly increasing"},
        BadUnit{"unknown_unit_header", "valve.csv", "q [l/min]", "q [gallons]", "valve.csv:1:5",
                "unit 'gallons' not accepted"},
        BadUnit{"unknown_unit_manifest", "unit.yaml", "\"50 mm\"", "\"50 inch\"",
                "unit.yaml:5:", "unit 'inch' not accepted"},
        BadUnit{"empty_file", "pipe.csv", "", "", "pipe.csv", "empty file"},
        BadUnit{"header_without_rows", "pipe.csv", "", "t,u,q_in,q_out\n", "pipe.csv:1",
                "header with no data rows"},
        BadUnit{"wrong_kind", "unit.yaml", "kind: valve", "kind: valves",
                "unit.yaml:11:", "expected valve | pipeline | stroke | validation"},
        BadUnit{"position_outside_stroke", "step.csv", "0.002,1,50,", "0.002,1,52,", "step.csv:4:3",
                "outside the stroke"},
        BadUnit{"position_wrong_origin", "unit.yaml", "position_origin: retracted",
                "position_origin: mid", "step.csv:4:3", "outside the stroke"},
        BadUnit{"duplicate_id", "unit.yaml", "id: pipe-38", "id: valve-1",
                "unit.yaml:12:", "duplicate experiment id 'valve-1'"},
        BadUnit{"absolute_file", "unit.yaml", "file: step.csv", "file: /etc/passwd",
                "unit.yaml:13:", "relative to the unit directory"},
        BadUnit{"file_escapes_unit", "unit.yaml", "file: step.csv", "file: ../unit/../../step.csv",
                "unit.yaml:13:", "outside the unit directory"},
        BadUnit{"non_positive_length", "unit.yaml", "stroke: \"50 mm\"", "stroke: \"-50 mm\"",
                "unit.yaml:5:", "non-physical"},
        BadUnit{"rod_not_smaller_than_bore", "unit.yaml", "rod: \"6 mm\"", "rod: \"16 mm\"",
                "unit.yaml:5:", "rod smaller than the bore"},
        BadUnit{"non_positive_pressure", "unit.yaml", "supply_pressure: \"5 bar\"",
                "supply_pressure: 0", "unit.yaml:4:", "non-physical"},
        BadUnit{"missing_tube_length", "unit.yaml", ", tube_length: \"38 cm\"", "",
                "unit.yaml:12:", "missing required key 'tube_length'"},
        BadUnit{"command_out_of_range", "valve.csv", "0.001,0.5,", "0.001,-0.5,", "valve.csv:3:2",
                "expected a command in [0, 1] V"},
        BadUnit{"unknown_sensor", "unit.yaml", "  q: {tau", "  qq: {tau",
                "unit.yaml:9:", "unknown column 'qq'"},
        BadUnit{"non_scalar_key", "unit.yaml", "unit: TEST-1\n", "unit: TEST-1\n? [a, b]\n: 1\n",
                "unit.yaml:3:", "expected a plain key"},
        BadUnit{"yaml_syntax", "unit.yaml", "orientation: horizontal", "orientation: [horizontal",
                "unit.yaml:", "YAML syntax error"}),
    [](const ::testing::TestParamInfo<BadUnit>& info) { return std::string(info.param.name); });

TEST(RigDataManifestTest, ParsesUnitStringsAndGaugeSupply) {
  const Manifest m = ParseManifest(
      "format: pneumaid-rig/1\nunit: A\nrig:\n  atmospheric_pressure: \"101.3 kPa\"\n"
      "  supply_pressure: \"4 bar_g\"\n  gas: {T: \"20 degC\"}\n  load_mass: \"150 g\"\n"
      "  cylinder: {dead_volume_1: \"0.101 cm3\"}\n"
      "experiments:\n  - {id: a, kind: stroke, file: a.csv}\n",
      "m.yaml");
  EXPECT_DOUBLE_EQ(m.rig.atmospheric_pressure_Pa, 101300.0);
  EXPECT_DOUBLE_EQ(m.rig.supply_pressure_Pa, 4e5 + 101300.0);
  EXPECT_DOUBLE_EQ(m.rig.gas.temperature_K, 293.15);
  EXPECT_DOUBLE_EQ(m.rig.load_mass_kg, 0.15);
  EXPECT_NEAR(m.rig.dead_volume_1_m3, 1.01e-7, 1e-20);
}

// A manifest the synthetic rig writes quotes a unit id, an experiment id or
// a file name that another YAML reader would take for a number, a bool or
// null (unit 0001 read as the integer 1), or that holds a character a flow
// mapping reads otherwise; the rest stays plain. Each reads back as written.
TEST(RigWriterTest, TextsAnotherReaderWouldMisreadAreQuoted) {
  Manifest manifest;
  manifest.unit = "0001";
  manifest.experiments = {{"1e3", ExperimentKind::kValve, "valve.csv", std::nullopt, 0},
                          {"step-1", ExperimentKind::kValidation, "step, 1.csv", std::nullopt, 0},
                          {"true", ExperimentKind::kStroke, "007.csv", std::nullopt, 0}};
  const YAML::Node root = YAML::Load(ManifestToYaml(manifest));
  const YAML::Node experiments = root["experiments"];
  // yaml-cpp tags a quoted scalar "!", a plain one "?".
  for (const YAML::Node& quoted : {root["unit"], experiments[0]["id"], experiments[1]["file"],
                                   experiments[2]["id"], experiments[2]["file"]})
    EXPECT_EQ(quoted.Tag(), "!") << quoted.as<std::string>();
  for (const YAML::Node& plain : {experiments[0]["file"], experiments[1]["id"]})
    EXPECT_EQ(plain.Tag(), "?") << plain.as<std::string>();
  EXPECT_EQ(root["unit"].as<std::string>(), "0001");
  EXPECT_EQ(experiments[1]["file"].as<std::string>(), "step, 1.csv");
}

}  // namespace
}  // namespace pneumaid
