#include <filesystem>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "commands.h"
#include "pneumaid/diagnose/diagnose.h"
#include "pneumaid/io/files.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/rig_data.h"

namespace pneumaid::cli {
namespace {

struct DiagnoseArgs {
  std::string params_path;
  std::string unit_dir;
  std::string out_dir;
  std::string json_path;
  int max_effects = 2;
  std::string effects;  // "a,b,..."
  int threads = 1;
  bool verbose = false;
};

std::vector<std::string> SplitList(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

int RunDiagnose(const DiagnoseArgs& args) {
  const Parameters params = LoadParams(args.params_path);
  const Unit unit = ReadUnit(args.unit_dir);
  DiagnoseOptions options;
  options.max_effects = args.max_effects;
  options.effects = SplitList(args.effects);
  options.threads = args.threads;
  if (args.verbose) options.log = [](const std::string& line) { std::cerr << line << "\n"; };
  DiagnoseResult result;
  try {
    result = Diagnose(params, unit, options);
  } catch (const InputError& error) {
    // The library names its option ("effects: ..."); the user typed a flag.
    const std::string object = "effects: ";
    if (error.file() != "diagnose options" || error.message().compare(0, object.size(), object))
      throw;
    throw InputError("--effects", 0, 0, error.message().substr(object.size()));
  }
  std::cout << result.BriefReport();
  // Everything is computed before anything is written; each file is atomic.
  const std::filesystem::path out(args.out_dir);
  std::filesystem::create_directories(out / "before");
  std::filesystem::create_directories(out / "after");
  for (const auto& [report, folder] :
       {std::make_pair(&result.before, "before"), std::make_pair(&result.after, "after")}) {
    for (const auto& e : report->experiments) {
      if (!e.simulation.ok()) continue;
      WriteFileAtomically((out / folder / (e.id + ".csv")).string(), ComparisonToCsv(e));
    }
  }
  SaveParams(result.params, (out / "params.yaml").string());
  WriteFileAtomically((out / "report.md").string(), result.MarkdownReport());
  const std::string json = DiagnoseToJson(result);
  WriteFileAtomically((out / "report.json").string(), json);
  if (!args.json_path.empty()) WriteFileAtomically(args.json_path, json);
  std::cout << "wrote " << (out / "report.md").string() << ", params.yaml, report.json, "
            << "before/ and after/ CSVs\n";
  return kSuccess;  // named or not: a base model that does not explain the logs is normal input
}

}  // namespace

CommandRunner AddDiagnoseCommand(CLI::App* app) {
  auto args = std::make_shared<DiagnoseArgs>();
  app->add_option("unit", args->unit_dir, "unit directory")->required();
  app->add_option("--params", args->params_path, "parameter set to diagnose (params-v1)")
      ->required();
  app->add_option("--out", args->out_dir,
                  "directory for report.md, params.yaml (augmented), report.json and the "
                  "before/after CSVs")
      ->required();
  app->add_option("--json", args->json_path, "also write the report (pneumaid-report/1) here");
  app->add_option("--max-effects", args->max_effects, "add at most this many effects")
      ->check(CLI::Range(0, 8))
      ->capture_default_str();
  app->add_option("--effects", args->effects,
                  "candidate effects, comma-separated (default: every one the set lacks)");
  app->add_option("--threads", args->threads, "candidate fits run in parallel")
      ->check(CLI::Range(1, 256));
  app->add_flag("--verbose", args->verbose, "progress on stderr");
  return [args]() { return RunDiagnose(*args); };
}

}  // namespace pneumaid::cli
