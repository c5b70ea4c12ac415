#include <algorithm>
#include <filesystem>
#include <iostream>
#include <iterator>
#include <map>
#include <string>
#include <vector>

#include "commands.h"
#include "pneumaid/diagnose/diagnose.h"
#include "pneumaid/io/files.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/model/effects.h"
#include "pneumaid/report/report.h"

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
  std::string html_path;
};

// The output directory is replaced as a whole: it must be new, empty, or an
// earlier diagnose's output (never a directory of other files).
void CheckOutDirectory(const std::string& out) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (!fs::exists(out, error)) return;
  const bool earlier =
      std::all_of(std::begin(kDiagnoseOutputFiles), std::end(kDiagnoseOutputFiles),
                  [&out](const char* name) { return fs::exists(fs::path(out) / name); });
  if (!fs::is_directory(out, error) || !(fs::is_empty(out, error) || earlier)) {
    throw InputError("--out", 0, 0,
                     out + " exists and is not an earlier diagnose output; not replacing it");
  }
}

int RunDiagnose(const DiagnoseArgs& args) {
  CheckOutDirectory(args.out_dir);
  std::vector<std::string> outputs = {args.json_path, args.html_path};
  for (const char* name : kDiagnoseOutputFiles)
    outputs.push_back(args.out_dir + "/" + name);  // the directory is replaced whole
  RefuseOverwritingInputs(outputs, {args.unit_dir, args.params_path});
  const Parameters params = LoadParams(args.params_path);
  const Unit unit = ReadUnitSayingWhatItAssumed(args.unit_dir);
  NoteASetOfAnotherUnit(args.params_path, params, unit);
  DiagnoseOptions options;
  options.max_effects = args.max_effects;
  options.effects = SplitList(args.effects);
  options.threads = args.threads;
  if (args.verbose) options.log = [](const std::string& line) { std::cerr << line << "\n"; };
  const DiagnoseResult result = NamingFlag("diagnose options", "effects", "--effects",
                                           [&] { return Diagnose(params, unit, options); });
  std::cout << result.BriefReport();
  // Everything is computed before anything is written, and the whole output
  // directory is replaced at once: no mix of this run's files and an older one's.
  std::map<std::string, std::string> files;
  for (const auto& [report, folder] :
       {std::make_pair(&result.before, "before"), std::make_pair(&result.after, "after")}) {
    for (const auto& e : report->experiments) {
      if (e.simulation.ok())
        files[std::string(folder) + "/" + FileNameOfId(e.id) + ".csv"] = ComparisonToCsv(e);
    }
  }
  files["params.yaml"] = ParamsToYaml(result.params);
  files["report.md"] = result.MarkdownReport();
  const std::string json = DiagnoseToJson(result);
  files["report.json"] = json;
  std::string html;
  if (!args.html_path.empty()) {
    html = DiagnoseReportHtml({files["report.md"], result.named_effects, params, result.params,
                               result.before, result.after},
                              unit, ReportOptions{});
  }
  ReplaceDirectoryAtomically(args.out_dir, files);
  if (!args.json_path.empty()) WriteFileAtomically(args.json_path, json);
  std::cout << "wrote " << args.out_dir << "/report.md, params.yaml, report.json, "
            << "before/ and after/ CSVs\n";
  WriteHtml(args.html_path, html);
  if (result.before.numerical_failure() || result.after.numerical_failure()) {
    std::cerr << "error: a simulation of the diagnosed runs failed; see report.md\n";
    return kNumericalFailure;
  }
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
  app->add_option("--json", args->json_path, "also write the report (pneumaid-report/1) here")
      ->check(InExistingDirectory);
  app->add_option("--max-effects", args->max_effects, "add at most this many effects")
      ->check(CLI::Range(0, static_cast<int>(EffectCatalog().size())))
      ->capture_default_str();
  app->add_option("--effects", args->effects,
                  "candidate effects, comma-separated (default: every one the set lacks)");
  app->add_option("--threads", args->threads, "candidate fits run in parallel")
      ->check(CLI::Range(1, 256));
  app->add_flag("--verbose", args->verbose, "progress on stderr");
  AddHtmlOption(app, &args->html_path);
  return [args]() { return RunDiagnose(*args); };
}

}  // namespace pneumaid::cli
