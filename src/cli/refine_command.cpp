#include <iostream>
#include <string>

#include "commands.h"
#include "pneumaid/ident/refine.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/report/report.h"

namespace pneumaid::cli {
namespace {

struct RefineArgs {
  std::string params_path;
  std::string unit_dir;
  std::string spec_path = DefaultConfig("fit-default.yaml");
  std::string out_path;
  int threads = 1;
  bool verbose = false;
  bool no_stick_creep = false;
  std::string html_path;
};

int RunRefine(const RefineArgs& args) {
  RefuseOverwritingInputs({args.out_path, args.html_path},
                          {args.unit_dir, args.params_path, args.spec_path});
  const Parameters start = LoadParams(args.params_path);
  const Unit unit = ReadUnitSayingWhatItAssumed(args.unit_dir);
  NoteASetOfAnotherUnit(args.params_path, start, unit);
  const FitSpec spec = LoadFitSpec(args.spec_path);
  RefineOptions options = RefineOptions::ForIdentify();
  options.fit_stick_creep = !args.no_stick_creep;
  options.threads = args.threads;
  if (args.verbose) options.log = [](const std::string& line) { std::cout << line << "\n"; };
  const RefineResult result = Refine(start, unit, spec, options);
  return ReportAndSave(result, unit, args.out_path, args.html_path);
}

}  // namespace

int ReportAndSave(const RefineResult& result, const Unit& unit, const std::string& out_path,
                  const std::string& html_path, const std::string& text_before) {
  std::cout << result.BriefReport();
  if (!result.has_values()) {
    std::cerr << "error: refinement failed: " << result.reason << " (nothing written)\n";
    return kNumericalFailure;
  }
  ReportOptions page;
  page.text_report = text_before + result.BriefReport();
  const std::string html = html_path.empty() ? "" : UnitReportHtml(result.params, unit, page);
  SaveParams(result.params, out_path);
  std::cout << "wrote " << out_path << "\n";
  WriteHtml(html_path, html);
  if (result.status == FitStatus::kNotExplained) {
    std::cerr << "error: " << result.reason
              << "\n  the start's coefficients are written, with that verdict and the refined "
                 "values (which absorb what the model lacks) in its provenance\n"
              << "  next: pneumaid diagnose " << unit.directory << " --params " << out_path
              << " --out DIR looks for the effect the model lacks (docs/diagnose.md)\n";
    return kNumericalFailure;
  }
  if (result.status != FitStatus::kConverged) {
    std::cerr << "warning: the refinement did not converge (" << result.reason
              << "); the parameters written are its best point\n";
    return kNumericalFailure;
  }
  return kSuccess;
}

CommandRunner AddRefineCommand(CLI::App* app) {
  auto args = std::make_shared<RefineArgs>();
  app->add_option("unit", args->unit_dir, "unit directory")->required();
  app->add_option("--params", args->params_path, "starting parameter set (params-v1)")->required();
  app->add_option("--spec", args->spec_path, "fit spec (pneumaid-fit/1)")->capture_default_str();
  app->add_option("--out", args->out_path,
                  "parameter set written (params-v1): the refined one, or the start where the "
                  "model does not explain the logs")
      ->required()
      ->check(InExistingDirectory);
  app->add_option("--threads", args->threads,
                  "experiments, and the friction screen's candidates, simulated in parallel")
      ->check(CLI::Range(1, 256));
  app->add_flag("--verbose", args->verbose, "print the solver's progress");
  app->add_flag("--no-stick-creep", args->no_stick_creep,
                "fit the spec's model only, no creep speed (effects.stick_creep.v; "
                "docs/refinement.md)");
  AddHtmlOption(app, &args->html_path);
  return [args]() { return RunRefine(*args); };
}

}  // namespace pneumaid::cli
