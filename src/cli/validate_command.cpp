#include <filesystem>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "commands.h"
#include "pneumaid/io/files.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/report/report.h"
#include "pneumaid/validate/validate.h"

namespace pneumaid::cli {
namespace {

struct ValidateArgs {
  std::string params_path;
  std::string unit_dir;
  std::string json_path;
  std::string csv_dir;
  std::vector<std::string> min_fit;   // "x=95"
  std::vector<std::string> max_rmse;  // "p1=1e4"
  std::vector<std::string> experiments;
  std::string html_path;
};

// "x=95" items into `thresholds`: a channel of the comparison and a number,
// which replaces that channel's default only (before, one --max-rmse dropped
// p2's check), or "off", which drops the channel's check.
void SetThresholds(const std::vector<std::string>& items, const std::string& option,
                   std::map<std::string, double>* thresholds) {
  const auto known = [](const std::string& channel) {
    for (const auto& c : kComparedChannels) {
      if (channel == c.name) return true;
    }
    return false;
  };
  const std::string expected =
      "CHANNEL=NUMBER or CHANNEL=off with CHANNEL one of x, p1, p2, q1, q2";
  for (const std::string& item : items) {
    const std::size_t eq = item.find('=');
    if (eq != std::string::npos && item.compare(eq + 1, std::string::npos, "off") == 0) {
      const std::string channel = item.substr(0, eq);
      if (!known(channel)) throw InputError(option, 0, 0, "'" + item + "': expected " + expected);
      thresholds->erase(channel);
      continue;
    }
    for (const auto& [channel, value] : ParseAssignments({item}, option, expected, known))
      (*thresholds)[channel] = value;
  }
}

int RunValidate(const ValidateArgs& args) {
  const Parameters params = LoadParams(args.params_path);
  const Unit unit = ReadUnitSayingWhatItAssumed(args.unit_dir);
  NoteASetOfAnotherUnit(args.params_path, params, unit);
  ValidationOptions options;
  options.experiment_ids = args.experiments;
  // No output may replace an input, each run's comparison CSV (named by its
  // id) included.
  const auto csv_path = [&args](const std::string& id) {
    return args.csv_dir + "/" + FileNameOfId(id) + "-validation.csv";
  };
  std::vector<std::string> outputs = {args.json_path, args.html_path};
  for (const Experiment& e : unit.experiments) {
    if (!args.csv_dir.empty() && options.Chooses(e)) outputs.push_back(csv_path(e.entry.id));
  }
  RefuseOverwritingInputs(outputs, {args.unit_dir, args.params_path});
  SetThresholds(args.min_fit, "--min-fit", &options.min_fit_percent);
  SetThresholds(args.max_rmse, "--max-rmse", &options.max_rmse);
  if (std::string error; !options.IsValid(&error)) {
    ThrowNamingTheFlag(error, {{"min_fit_percent: ", "--min-fit"}, {"max_rmse: ", "--max-rmse"}});
    throw InputError("validation options", 0, 0, error);
  }
  const ValidationReport report = ValidateUnit(params, unit, options);
  std::cout << report.BriefReport();
  ReportOptions page;
  page.text_report = report.BriefReport();
  const std::string html =
      args.html_path.empty() ? "" : UnitReportHtml(params, unit, page, &report);
  // Everything is computed before anything is written; each file is atomic.
  if (!args.csv_dir.empty()) MakeOutputDirectory(args.csv_dir);
  if (!args.json_path.empty()) WriteFileAtomically(args.json_path, ReportToJson(report));
  if (!args.csv_dir.empty()) {
    for (const auto& e : report.experiments) {
      if (!e.simulation.ok()) continue;
      WriteFileAtomically(csv_path(e.id), ComparisonToCsv(e));
    }
  }
  WriteHtml(args.html_path, html);
  if (report.numerical_failure()) return kNumericalFailure;
  return report.thresholds_met() ? kSuccess : kQualityMissed;
}

}  // namespace

CommandRunner AddValidateCommand(CLI::App* app) {
  auto args = std::make_shared<ValidateArgs>();
  app->add_option("--params", args->params_path, "parameter set (params-v1)")->required();
  app->add_option("unit", args->unit_dir, "unit directory")->required();
  app->add_option("--json", args->json_path, "write the report (pneumaid-report/1) here")
      ->check(InExistingDirectory);
  app->add_option("--csv-out", args->csv_dir,
                  "write measured-vs-simulated CSVs into this directory")
      ->check(DirectoryToWrite);
  app->add_option("--min-fit", args->min_fit,
                  "CHANNEL=PERCENT: lowest NRMSE fit accepted (default x=95; repeatable; "
                  "replaces that channel's default only; CHANNEL=off drops its check)");
  app->add_option("--max-rmse", args->max_rmse,
                  "CHANNEL=VALUE: highest RMSE accepted, SI (default p1=1e4 p2=1e4 Pa; "
                  "repeatable; replaces that channel's default only; CHANNEL=off drops its check)");
  app->add_option("--experiment", args->experiments,
                  "validate these experiment ids (default: every validation run; repeatable)");
  AddHtmlOption(app, &args->html_path);
  return [args]() { return RunValidate(*args); };
}

}  // namespace pneumaid::cli
