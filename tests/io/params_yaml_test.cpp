#include "pneumaid/io/params_yaml.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>

#include "../../src/io/provenance_map.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/model/parameter_table.h"

namespace pneumaid {
namespace {

const std::string kConfigs = std::string(PNEUMAID_SOURCE_DIR) + "/configs/";

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

TEST(ParamsYamlTest, PaperConfigEqualsTheBuiltInDefaults) {
  const Parameters loaded = LoadParams(kConfigs + "paper.yaml");
  const Parameters defaults;
  for (const auto& info : ScalarParameterTable()) {
    EXPECT_EQ(info.get(loaded), info.get(defaults)) << info.path;
  }
  EXPECT_EQ(loaded.cylinder.orientation, Orientation::kVertical);
  const Parameters horizontal = LoadParams(kConfigs + "paper-horizontal.yaml");
  EXPECT_EQ(horizontal.cylinder.orientation, Orientation::kHorizontal);
}

TEST(ParamsYamlTest, RoundTripIsExact) {
  Parameters p = LoadParams(kConfigs + "paper.yaml");
  p.friction.positive.viscous_N_s_per_m = 0.1 + 0.2;  // not a short decimal
  p.pipeline.delta_by_length = {{0.09, 8.1}, {1.2, 7.7}};
  p.effects["valve_lag"] = {{"tau", 0.004}};
  p.uncertainty["friction.positive.Fs"] = 0.25;
  p.valve.branch = ValveBranchMode::kHysteresis;
  p.pipeline.model = PipelineModel::kFlowLag;
  const Parameters back = ParamsFromYaml(ParamsToYaml(p), "round-trip");
  for (const auto& info : ScalarParameterTable())
    EXPECT_EQ(info.get(back), info.get(p)) << info.path;
  ASSERT_EQ(back.pipeline.delta_by_length.size(), 2u);
  EXPECT_EQ(back.pipeline.delta_by_length[1].delta_per_s, 7.7);
  EXPECT_EQ(back.effects, p.effects);
  EXPECT_EQ(back.uncertainty, p.uncertainty);
  EXPECT_EQ(back.valve.branch, ValveBranchMode::kHysteresis);
  EXPECT_EQ(back.pipeline.model, PipelineModel::kFlowLag);
  EXPECT_NE(ParamsToYaml(back).find("seed paper, Section 3"), std::string::npos);
}

// A unit id that another YAML reader would take for a number, a bool or null
// is written quoted (PyYAML read `unit: 0001` as the integer 1); any other
// stays plain. Each reads back as written.
TEST(ParamsYamlTest, AUnitIdThatReadsAsANumberIsQuoted) {
  Parameters p = LoadParams(kConfigs + "paper.yaml");
  for (const char* id : {"0001", "1e3", ".nan", "-5", "true", "No", "null", "y"}) {
    p.unit = id;
    const std::string text = ParamsToYaml(p);
    EXPECT_NE(text.find(std::string("\nunit: \"") + id + "\"\n"), std::string::npos) << text;
    EXPECT_EQ(ParamsFromYaml(text, "quoted").unit, id);
  }
  for (const char* id : {"PVQ13-0001", "sweep-07", "unit_1.a", "nano"}) {
    p.unit = id;
    const std::string text = ParamsToYaml(p);
    EXPECT_NE(text.find(std::string("\nunit: ") + id + "\n"), std::string::npos) << text;
    EXPECT_EQ(ParamsFromYaml(text, "plain").unit, id);
  }
}

// So is every text the provenance holds (its unit, a date, a file, a digest
// that starts with digits, a held coefficient's reason), in the parameter
// file and in the provenance text alike; its numbers stay numbers.
TEST(ParamsYamlTest, TheProvenancesTextsThatReadAsNumbersAreQuoted) {
  Parameters p = LoadParams(kConfigs + "paper.yaml");
  p.unit = "0001";
  p.provenance_yaml =
      "{unit: \"0001\", date: \"2026-11-30T14:55:49Z\", inputs: [{file: \"007\", sha256: "
      "\"1234\"}], held: {friction.positive.vs: \"1e3\"}, friction: {final_cost: 2.5, segments: "
      "12}}";
  for (const std::string& text :
       {ParamsToYaml(p), WithProvenanceEntry(p.provenance_yaml, "x", YAML::Node("y"))}) {
    for (const char* quoted : {"unit: \"0001\"", "date: \"2026-11-30T14:55:49Z\"", "file: \"007\"",
                               "sha256: \"1234\"", "friction.positive.vs: \"1e3\""})
      EXPECT_NE(text.find(quoted), std::string::npos) << quoted << " in " << text;
    for (const char* plain : {"final_cost: 2.5", "segments: 12"})
      EXPECT_NE(text.find(plain), std::string::npos) << plain << " in " << text;
  }
  const Parameters back = ParamsFromYaml(ParamsToYaml(p), "quoted");
  // Read back, the provenance text keeps them quoted (exports and reports
  // carry it as it is).
  for (const char* quoted : {"unit: \"0001\"", "date: \"2026-11-30T14:55:49Z\""})
    EXPECT_NE(back.provenance_yaml.find(quoted), std::string::npos) << back.provenance_yaml;
  const YAML::Node provenance = YAML::Load(back.provenance_yaml);
  EXPECT_EQ(provenance["unit"].as<std::string>(), "0001");
  EXPECT_EQ(provenance["inputs"][0]["file"].as<std::string>(), "007");
}

// A set built in code may carry provenance that is free text, or not YAML at
// all: it is written under `given` (it used to be dropped, or to throw
// yaml-cpp's parser error out of SaveParams), and what the loader reads back
// is a mapping again.
TEST(ParamsYamlTest, ProvenanceThatIsNotAMappingIsWrittenUnderGiven) {
  Parameters p = LoadParams(kConfigs + "paper.yaml");
  for (const std::string text : {"measured on rig 3", "[unbalanced", "~", "{a: 1}", ""}) {
    p.provenance_yaml = text;
    std::string yaml;
    ASSERT_NO_THROW(yaml = ParamsToYaml(p)) << text;
    const Parameters back = ParamsFromYaml(yaml, "provenance");
    if (text == "{a: 1}") {
      EXPECT_EQ(back.provenance_yaml, "{a: 1}");
    } else if (text.empty()) {
      EXPECT_NE(yaml.find("provenance: {}"), std::string::npos);
    } else {
      EXPECT_NE(back.provenance_yaml.find("given"), std::string::npos) << back.provenance_yaml;
      EXPECT_NE(back.provenance_yaml.find(text), std::string::npos) << back.provenance_yaml;
    }
  }
}

// pipeline.model is the one choice with a default (the format's:
// conductance_lag).
TEST(ParamsYamlTest, APipelineModelLeftOutIsTheConductanceLag) {
  std::string text = ReadText(kConfigs + "paper.yaml");
  const std::string model = "  model: conductance_lag\n";
  ASSERT_NE(text.find(model), std::string::npos);
  text.erase(text.find(model), model.size());
  text.replace(text.find("delta: 8.0"), 10, "delta: 7.0");  // the set read is this one
  const Parameters p = ParamsFromYaml(text, "no-model.yaml");
  EXPECT_EQ(p.pipeline.delta_per_s, 7.0);
  EXPECT_EQ(p.pipeline.model, PipelineModel::kConductanceLag);
}

// A document may open with '---' (one document).
TEST(ParamsYamlTest, ADocumentMayOpenWithItsMarker) {
  const std::string text = ReadText(kConfigs + "paper.yaml");
  EXPECT_EQ(ParamsFromYaml("---\n" + text, "marked.yaml").unit, "paper");
  EXPECT_EQ(ParamsFromYaml(text + "---\n", "trailing.yaml").unit, "paper");  // nothing after it
}

struct BadCase {
  const char* name;
  const char* find;     // text in paper.yaml to replace
  const char* replace;  // with this
  int line;             // where the message must point
  const char* message;  // a part of the message
};

class ParamsYamlBadInputTest : public ::testing::TestWithParam<BadCase> {};

TEST_P(ParamsYamlBadInputTest, NamesFileLineAndExpectation) {
  const BadCase& c = GetParam();
  std::string text = ReadText(kConfigs + "paper.yaml");
  const auto at = text.find(c.find);
  ASSERT_NE(at, std::string::npos) << c.find;
  text.replace(at, std::string(c.find).size(), c.replace);
  try {
    ParamsFromYaml(text, "bad.yaml");
    FAIL() << "accepted " << c.name;
  } catch (const InputError& error) {
    EXPECT_EQ(error.file(), "bad.yaml");
    EXPECT_EQ(error.line(), c.line) << error.what();
    EXPECT_NE(std::string(error.what()).find(c.message), std::string::npos) << error.what();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Cases, ParamsYamlBadInputTest,
    ::testing::Values(
        BadCase{"unknown_top_key", "effects: {}", "effects: {}\ncolour: blue", 32,
                "unknown key 'colour' (expected cylinder, effects, format, friction, gas, "
                "pipeline, provenance, supply, uncertainty, unit, valve)"},
        BadCase{"unknown_nested_key", "  stroke: 0.05", "  stroke: 0.05\n  strok: 0.05", 12,
                "unknown key 'cylinder.strok' (expected area_1, area_2, dead_volume_1, "
                "dead_volume_2, load_mass, orientation, stroke)"},
        BadCase{"missing_key", "  load_mass: 0.15\n", "", 9,
                "missing required key 'cylinder.load_mass'"},
        // The model's choices are required too (a missing orientation was
        // taken as vertical: a horizontal unit simulated with gravity).
        BadCase{"missing_orientation", "  orientation: vertical\n", "", 9,
                "missing required key 'cylinder.orientation' (vertical | horizontal)"},
        BadCase{"missing_branch", "  branch: increasing\n", "", 17,
                "missing required key 'valve.branch'"},
        BadCase{"missing_friction_model", "  model: stribeck\n", "", 28,
                "missing required key 'friction.model' (stribeck)"},
        BadCase{"negative_length_by_length", "  delta_by_length: []",
                "  delta_by_length:\n    - {tube_length: 0.09, delta: 8.1}\n    - {tube_length: "
                "-0.09, delta: 8.1}",
                28, "pipeline.delta_by_length[1]"},
        BadCase{"unit_not_an_id", "unit: paper", "unit: pa per", 5,
                "unit: expected an id of letters, digits"},
        // Two files run together: the second would be dropped unread.
        BadCase{"second_document", "provenance: {source:",
                "---\nunit: other\n---\nprovenance: {source:", 34, "a second YAML document"},
        // A missing subsection is named at its section's line, not the file's first.
        BadCase{"missing_subsection",
                "  decreasing: {a: 9.86, b: -19.30, c: 10.95, d: -0.21, q_max: 9.15e-5, u_sat: "
                "0.75}\n",
                "", 17, "missing required key 'valve.decreasing.a'"},
        BadCase{"negative_volume", "dead_volume_1: 1.01e-7", "dead_volume_1: -1.01e-7", 12,
                "cylinder.dead_volume_1"},
        BadCase{"u_sat_above_one", "q_max: 9.25e-5, u_sat: 0.75", "q_max: 9.25e-5, u_sat: 1.5", 19,
                "u_sat"},
        BadCase{"not_a_number", "delta: 8.0", "delta: fast", 24, "expected a finite number"},
        BadCase{"duplicate_key", "delta: 8.0", "delta: 8.0\n  delta: 2.0", 25,
                "duplicate key 'delta'"},
        BadCase{"wrong_format", "pneumaid-params/1", "pneumaid-params/2", 4, "format"},
        BadCase{"bad_enum", "branch: increasing", "branch: sideways", 21,
                "expected increasing | decreasing | hysteresis, got 'sideways'"},
        BadCase{"unknown_effect", "effects: {}", "effects: {warp: {x: 1}}", 31,
                "unknown effect 'warp'"},
        BadCase{"effect_missing_parameter", "effects: {}", "effects: {valve_lag: {}}", 31,
                "missing parameter"},
        BadCase{"rod_larger_than_piston", "area_2: 1.73e-4", "area_2: 3.0e-4", 10,
                "smaller than area_1"},
        BadCase{"uncertainty_unknown_path", "uncertainty: {}", "uncertainty: {friction.up.Fs: 1}",
                32, "names no parameter"},
        BadCase{"non_scalar_key", "effects: {}", "effects: {[a]: 1}", 31, "expected a plain key"},
        // A key with nothing after it: its own line, not the next key's.
        BadCase{"empty_mapping", "effects: {}", "effects:", 31,
                "effects: expected a value after the key, got none"},
        BadCase{"empty_value", "delta: 8.0", "delta:", 24,
                "pipeline.delta: expected a value after the key, got none"},
        BadCase{"yaml_syntax", "gas: {k: 1.4, R: 287.0, T: 293.0}",
                "gas: {k: 1.4, R: [287.0, T: 293.0}", 6, "YAML syntax"}),
    [](const ::testing::TestParamInfo<BadCase>& info) { return std::string(info.param.name); });

TEST(ParamsYamlTest, SaveRefusesInvalidAndLeavesNoFile) {
  const std::string path = ::testing::TempDir() + "/pneumaid_invalid_params.yaml";
  std::filesystem::remove(path);
  Parameters p;
  p.cylinder.stroke_m = -1;
  EXPECT_THROW(SaveParams(p, path), InputError);
  EXPECT_FALSE(std::filesystem::exists(path));
  SaveParams(Parameters{}, path);
  EXPECT_EQ(LoadParams(path).cylinder.stroke_m, 0.05);
  std::filesystem::remove(path);
}

TEST(ParamsYamlTest, FormatDoubleIsShortestRoundTrip) {
  EXPECT_EQ(FormatDouble(0.15), "0.15");
  EXPECT_EQ(FormatDouble(5e5), "500000");
  EXPECT_EQ(std::stod(FormatDouble(0.1 + 0.2)), 0.1 + 0.2);
}

}  // namespace
}  // namespace pneumaid
