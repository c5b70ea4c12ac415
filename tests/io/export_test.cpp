// Exports for controller teams, read back: the ROS 2 file by yaml-cpp, the C
// header compiled as C99 and as C++17 and its constants printed, the MATLAB
// script line by line, the JSON's values; every value equal to the set's.
#include "pneumaid/io/export.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/model/parameter_table.h"

namespace pneumaid {
namespace {

namespace fs = std::filesystem;

Parameters Identified() {
  Parameters p = LoadParams(std::string(PNEUMAID_SOURCE_DIR) + "/datasets/paper-rig/truth.yaml");
  p.unit = "PVQ13-0007";
  p.friction.positive.static_force_N = 10.123456789012345;  // all 17 digits matter
  p.effects["valve_lag"] = {{"tau", 0.0315}};
  p.uncertainty["friction.positive.Fs"] = 0.0123;
  p.provenance_yaml = "{tool: pneumaid test, note: \"a 'quoted' */ comment\"}";
  return p;
}

std::string Export(const Parameters& p, ExportFormat format) {
  ExportOptions options;
  options.format = format;
  options.ros2_node = "actuator_controller";
  return ExportParameters(p, options);
}

TEST(ExportTest, Ros2ParsesAndHoldsEveryParameter) {
  const Parameters p = Identified();
  const YAML::Node root = YAML::Load(Export(p, ExportFormat::kRos2));
  const YAML::Node node = root["actuator_controller"]["ros__parameters"];
  ASSERT_TRUE(node.IsMap());
  EXPECT_EQ(node["unit"].as<std::string>(), "PVQ13-0007");
  for (const ScalarParameterInfo& info : ScalarParameterTable()) {
    YAML::Node at = node;
    std::stringstream path(info.path);
    for (std::string part; std::getline(path, part, '.');) at.reset(at[part]);
    ASSERT_TRUE(at.IsScalar()) << info.path;
    EXPECT_EQ(at.as<double>(), info.get(p)) << info.path;
  }
  EXPECT_EQ(node["effects"]["valve_lag"]["tau"].as<double>(), 0.0315);
}

// The node key follows ROS 2's rules for node names, namespaces and
// wildcards; a key with no node in it, or one YAML reads as an alias (`*`),
// is refused, naming the option.
TEST(ExportTest, Ros2NodeKeysFollowRos2sNames) {
  Parameters params;
  ExportOptions options;
  options.format = ExportFormat::kRos2;
  for (const char* node : {"pneumaid", "actuator_1", "/ns/node", "/**", "/ns/*", "ns/node"}) {
    options.ros2_node = node;
    const YAML::Node root = YAML::Load(ExportParameters(params, options));
    EXPECT_TRUE(root[node]["ros__parameters"].IsMap()) << node;
  }
  for (const char* node : {"", "/", "//", "a//b", "ns/", "1node", "/ns/2", "bad node", "a:b", "*",
                           "**", "*/x", "a/*"}) {
    options.ros2_node = node;
    try {
      ExportParameters(params, options);
      ADD_FAILURE() << "exported with node '" << node << "'";
    } catch (const InputError& error) {
      EXPECT_EQ(error.message().rfind("ros2_node: ", 0), 0u) << error.what();
    }
  }
  options.format = ExportFormat::kJson;  // no node in it: not read
  options.ros2_node = "/";
  EXPECT_NO_THROW(ExportParameters(params, options));
}

// The header compiled by the system's C and C++ compilers; a program prints
// each constant with 17 digits, which must read back as the set's value.
TEST(ExportTest, CHeaderCompilesAsC99AndCxx17WithTheExactValues) {
  const Parameters p = Identified();
  const fs::path dir = fs::path(::testing::TempDir()) / "export_c";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "params.h") << Export(p, ExportFormat::kCHeader);
  std::ostringstream program;
  program << "#include <stdio.h>\n#include \"params.h\"\nint main(void) {\n"
          << "  printf(\"%s\\n\", PNEUMAID_UNIT_ID);\n";
  for (const ScalarParameterInfo& info : ScalarParameterTable()) {
    std::string id = "PNEUMAID_";
    for (char c : std::string(info.path))
      id += std::isalnum(static_cast<unsigned char>(c)) ? std::toupper(c) : '_';
    program << "  printf(\"%.17g\\n\", " << id << ");\n";
  }
  program << "  printf(\"%.17g\\n\", PNEUMAID_EFFECTS_VALVE_LAG_TAU);\n  return 0;\n}\n";
  std::ofstream(dir / "main.c") << program.str();
  fs::copy_file(dir / "main.c", dir / "main.cpp");
  for (const std::string& compile :
       {"cc -std=c99 -Wall -Werror -pedantic -o " + (dir / "c").string() + " " +
            (dir / "main.c").string(),
        "c++ -std=c++17 -Wall -Werror -pedantic -o " + (dir / "cxx").string() + " " +
            (dir / "main.cpp").string()}) {
    ASSERT_EQ(std::system(compile.c_str()), 0) << compile;
  }
  for (const char* binary : {"c", "cxx"}) {
    const std::string out = (dir / (std::string(binary) + ".txt")).string();
    ASSERT_EQ(std::system(((dir / binary).string() + " > " + out).c_str()), 0);
    std::ifstream in(out);
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line, "PVQ13-0007");
    for (const ScalarParameterInfo& info : ScalarParameterTable()) {
      std::getline(in, line);
      EXPECT_EQ(std::strtod(line.c_str(), nullptr), info.get(p)) << binary << " " << info.path;
    }
    std::getline(in, line);
    EXPECT_EQ(std::strtod(line.c_str(), nullptr), 0.0315);
  }
}

// No MATLAB or Octave here: every line of the script is a comment, an
// assignment of a number or a string to a field of pneumaid_params, or the
// struct's creation (a syntax check).
TEST(ExportTest, MatlabScriptIsAssignmentsOfEveryParameter) {
  const Parameters p = Identified();
  const std::string script = Export(p, ExportFormat::kMatlab);
  const std::regex comment("^%.*$");
  const std::regex create("^pneumaid_(params|model) = struct\\(\\);$");
  const std::regex number(
      "^pneumaid_params\\.([A-Za-z][A-Za-z0-9_]*(?:\\.[A-Za-z][A-Za-z0-9_]*)*) = "
      "(-?[0-9][0-9.eE+-]*|-?inf|nan);  % .*$");
  const std::regex text("^pneumaid_(params|model)\\.[a-z]+(\\.[a-z_]+)* = '([^']|'')*';(  % .*)?$");
  std::map<std::string, double> values;
  std::stringstream lines(script);
  for (std::string line; std::getline(lines, line);) {
    std::smatch m;
    if (std::regex_match(line, m, number)) {
      values[m[1]] = std::strtod(m[2].str().c_str(), nullptr);
      continue;
    }
    EXPECT_TRUE(std::regex_match(line, comment) || std::regex_match(line, create) ||
                std::regex_match(line, text))
        << "not MATLAB this check knows: " << line;
  }
  for (const ScalarParameterInfo& info : ScalarParameterTable())
    EXPECT_EQ(values[info.path], info.get(p)) << info.path;
  EXPECT_EQ(values["effects.valve_lag.tau"], 0.0315);
  EXPECT_NE(script.find("PVQ13-0007"), std::string::npos);
}

// A controller needs the model's choices as much as its numbers: gravity
// acts on a vertical rod only, a pipeline of model none uses no delta.
TEST(ExportTest, EveryFormatStatesTheModelsChoices) {
  Parameters p = Identified();
  p.cylinder.orientation = Orientation::kHorizontal;
  p.pipeline.model = PipelineModel::kNone;
  const YAML::Node ros2 =
      YAML::Load(Export(p, ExportFormat::kRos2))["actuator_controller"]["ros__parameters"];
  EXPECT_EQ(ros2["cylinder"]["orientation"].as<std::string>(), "horizontal");
  EXPECT_EQ(ros2["pipeline"]["model"].as<std::string>(), "none");
  EXPECT_EQ(ros2["valve"]["branch"].as<std::string>(), ToString(p.valve.branch));
  EXPECT_EQ(ros2["cylinder"]["stroke"].as<double>(), p.cylinder.stroke_m);  // the numbers beside
  // JSON's and MATLAB's parameters stay numbers (a Simulink parameter struct
  // must be); the choices have their own object and struct.
  const YAML::Node json = YAML::Load(Export(p, ExportFormat::kJson));
  EXPECT_EQ(json["model"]["cylinder.orientation"].as<std::string>(), "horizontal");
  EXPECT_EQ(json["model"]["friction.model"].as<std::string>(), "stribeck");
  EXPECT_FALSE(json["parameters"]["cylinder.orientation"]);
  EXPECT_NE(Export(p, ExportFormat::kCHeader)
                .find("#define PNEUMAID_CYLINDER_ORIENTATION \"horizontal\" /* vertical: gravity"),
            std::string::npos);
  const std::string script = Export(p, ExportFormat::kMatlab);
  EXPECT_NE(script.find("pneumaid_model.pipeline.model = 'none';"), std::string::npos);
  EXPECT_EQ(script.find("pneumaid_params.pipeline.model"), std::string::npos);
}

TEST(ExportTest, JsonAndEveryFormatStateTheUnitAndProvenance) {
  const Parameters p = Identified();
  for (ExportFormat format :
       {ExportFormat::kRos2, ExportFormat::kCHeader, ExportFormat::kMatlab, ExportFormat::kJson}) {
    const std::string text = Export(p, format);
    EXPECT_NE(text.find("PVQ13-0007"), std::string::npos);
    EXPECT_NE(text.find(format == ExportFormat::kJson ? "\"tool\": \"pneumaid test\""
                                                      : "tool: pneumaid test"),
              std::string::npos)
        << text;
  }
  const YAML::Node json = YAML::Load(Export(p, ExportFormat::kJson));  // JSON is YAML
  EXPECT_EQ(json["parameters"]["friction.positive.Fs"]["value"].as<double>(),
            p.friction.positive.static_force_N);
  EXPECT_EQ(json["parameters"]["friction.positive.Fs"]["standard_error"].as<double>(), 0.0123);
  EXPECT_EQ(json["parameters"]["friction.positive.Fs"]["unit"].as<std::string>(), "N");
  ExportFormat format;
  EXPECT_TRUE(ParseExportFormat("c-header", &format));
  EXPECT_EQ(format, ExportFormat::kCHeader);
  EXPECT_FALSE(ParseExportFormat("fortran", &format));
}

// The tube lag identify measured at each tube length reaches every format as
// two lists of one length (a controller on another tube reads its delta off
// them); a set without them has none. The C lists compile as array
// initializers with their counts.
TEST(ExportTest, EveryFormatCarriesTheDeltaMeasuredAtEachTubeLength) {
  Parameters p = Identified();
  p.pipeline.delta_by_length = {{0.09, 19.25}, {0.38, 8.5}, {1.2, 3.0000000000000004}};
  const std::vector<double> lengths = {0.09, 0.38, 1.2}, deltas = {19.25, 8.5, 3.0000000000000004};
  const YAML::Node ros2 =
      YAML::Load(Export(p, ExportFormat::kRos2))["actuator_controller"]["ros__parameters"];
  const YAML::Node json = YAML::Load(Export(p, ExportFormat::kJson))["parameters"];
  EXPECT_EQ(json["pipeline.delta_by_length.delta"]["unit"].as<std::string>(), "1/s");
  for (const auto& [name, values] :
       {std::make_pair("tube_length", lengths), std::make_pair("delta", deltas)}) {
    EXPECT_EQ(ros2["pipeline"]["delta_by_length"][name].as<std::vector<double>>(), values);
    EXPECT_EQ(
        json[std::string("pipeline.delta_by_length.") + name]["value"].as<std::vector<double>>(),
        values);
  }
  EXPECT_EQ(ros2["pipeline"]["delta"].as<double>(), p.pipeline.delta_per_s);  // still there
  EXPECT_NE(Export(p, ExportFormat::kMatlab)
                .find("pneumaid_params.pipeline.delta_by_length.delta = [19.25 8.5 "
                      "3.0000000000000004];"),
            std::string::npos);
  const fs::path dir = fs::path(::testing::TempDir()) / "export_c_lists";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "params.h") << Export(p, ExportFormat::kCHeader);
  std::ofstream(dir / "main.c")
      << "#include <stdio.h>\n#include \"params.h\"\nint main(void) {\n"
      << "  static const double l[] = PNEUMAID_PIPELINE_DELTA_BY_LENGTH_TUBE_LENGTH;\n"
      << "  static const double d[PNEUMAID_PIPELINE_DELTA_BY_LENGTH_DELTA_COUNT] =\n"
      << "      PNEUMAID_PIPELINE_DELTA_BY_LENGTH_DELTA;\n"
      << "  int i;\n  for (i = 0; i < PNEUMAID_PIPELINE_DELTA_BY_LENGTH_TUBE_LENGTH_COUNT; ++i)\n"
      << "    printf(\"%.17g %.17g\\n\", l[i], d[i]);\n  return 0;\n}\n";
  const std::string binary = (dir / "c").string(), out = (dir / "c.txt").string();
  ASSERT_EQ(std::system(("cc -std=c99 -Wall -Werror -pedantic -o " + binary + " " +
                         (dir / "main.c").string())
                            .c_str()),
            0);
  ASSERT_EQ(std::system((binary + " > " + out).c_str()), 0);
  std::ifstream in(out);
  for (std::size_t i = 0; i < lengths.size(); ++i) {
    double length = 0, delta = 0;
    in >> length >> delta;
    EXPECT_EQ(length, lengths[i]);
    EXPECT_EQ(delta, deltas[i]);
  }
  p.pipeline.delta_by_length.clear();
  for (ExportFormat format :
       {ExportFormat::kRos2, ExportFormat::kCHeader, ExportFormat::kMatlab, ExportFormat::kJson})
    EXPECT_EQ(Export(p, format).find("delta_by_length"), std::string::npos);
}

// JSON's provenance is an object a program reads field by field: plain YAML
// numbers as numbers, quoted ones and other text as strings; text that is not
// a mapping under "given".
TEST(ExportTest, JsonCarriesTheProvenanceAsAnObject) {
  Parameters p = Identified();
  p.provenance_yaml =
      "{tool: pneumaid test, inputs: [{file: a.csv, sha256: 0e5f}], friction: {final_cost: "
      "22547.45, iterations: 93, status: converged}, code: '007', ok: true, unit: 12345, "
      "plain: 007, big: 1e999}";
  const YAML::Node json = YAML::Load(Export(p, ExportFormat::kJson));
  const YAML::Node provenance = json["provenance"];
  ASSERT_TRUE(provenance.IsMap()) << Export(p, ExportFormat::kJson);
  EXPECT_EQ(provenance["tool"].as<std::string>(), "pneumaid test");
  EXPECT_EQ(provenance["inputs"][0]["sha256"].as<std::string>(), "0e5f");
  EXPECT_EQ(provenance["friction"]["final_cost"].as<double>(), 22547.45);
  const std::string text = Export(p, ExportFormat::kJson);
  EXPECT_NE(text.find("\"final_cost\": 22547.45,"), std::string::npos) << text;
  EXPECT_NE(text.find("\"iterations\": 93,"), std::string::npos) << text;
  EXPECT_NE(text.find("\"code\": \"007\""), std::string::npos) << text;
  EXPECT_NE(text.find("\"ok\": true"), std::string::npos) << text;
  // Text stays text where yaml-cpp writes it unquoted (a unit id of digits);
  // what JSON does not spell as a finite number is a string.
  EXPECT_NE(text.find("\"unit\": \"12345\""), std::string::npos) << text;
  EXPECT_NE(text.find("\"plain\": \"007\""), std::string::npos) << text;
  EXPECT_NE(text.find("\"big\": \"1e999\""), std::string::npos) << text;
  p.provenance_yaml = "made by hand";
  EXPECT_NE(Export(p, ExportFormat::kJson).find("\"provenance\": {\"given\": \"made by hand\"}"),
            std::string::npos)
      << Export(p, ExportFormat::kJson);
}

}  // namespace
}  // namespace pneumaid
