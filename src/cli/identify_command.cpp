#include <ctime>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>

#include "commands.h"
#include "pneumaid/ident/identify.h"
#include "pneumaid/ident/refine.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/report/report.h"

namespace pneumaid::cli {
namespace {

struct IdentifyArgs {
  std::string unit_dir;
  std::string only;  // "valve,pipeline"
  std::string prior_path = DefaultConfig("paper.yaml");
  std::string out_path;
  bool refine = false;
  bool fit_u_sat = false;  // accepted: fitting u_sat is the default
  bool fix_u_sat = false;
  bool no_stick_creep = false;
  std::string spec_path = DefaultConfig("fit-default.yaml");
  int threads = 1;
  std::string html_path;
};

std::set<Component> ParseComponents(const std::string& list) {
  std::set<Component> out;
  std::stringstream items(list);
  for (std::string item; std::getline(items, item, ',');) {
    if (item == "valve") {
      out.insert(Component::kValve);
    } else if (item == "pipeline") {
      out.insert(Component::kPipeline);
    } else if (item == "friction") {
      out.insert(Component::kFriction);
    } else {
      throw InputError("--only", 0, 0, "'" + item + "': expected valve, pipeline or friction");
    }
  }
  return out;
}

int RunIdentify(const IdentifyArgs& args) {
  RefuseOverwritingInputs({args.out_path, args.html_path},
                          {args.unit_dir, args.prior_path, args.spec_path});
  const Parameters prior = LoadParams(args.prior_path);
  const Unit unit = ReadUnitSayingWhatItAssumed(args.unit_dir);
  IdentifyOptions options;
  if (!args.only.empty()) {
    options.components = ParseComponents(args.only);
    options.components_explicit = true;
  }
  options.valve.fit_u_sat = !args.fix_u_sat;
  options.tool_version = PNEUMAID_VERSION;
  options.date = UtcNow();
  // A unit the refinement would refuse is refused before the component fits.
  std::optional<FitSpec> spec;
  RefineOptions refine = RefineOptions::ForIdentify();
  refine.fit_stick_creep = !args.no_stick_creep;
  refine.threads = args.threads;
  if (args.refine) {
    spec = LoadFitSpec(args.spec_path);
    CheckRefinable(prior, unit, *spec, refine);
  }
  IdentifyReport report;
  Parameters identified;
  try {
    identified = Identify(unit, prior, options, &report);
  } catch (const InputError& error) {
    // The library names its options' objects; here they are flags.
    const std::string object = "components: ";
    if (error.message().compare(0, object.size(), object) != 0) throw;
    throw InputError(error.file(), error.line(), 0,
                     "--only " + error.message().substr(object.size()));
  }
  std::cout << report.BriefReport();
  if (args.refine) {
    return ReportAndSave(Refine(identified, unit, *spec, refine), unit, args.out_path,
                         args.html_path, report.BriefReport());
  }
  ReportOptions page;
  page.text_report = report.BriefReport();
  const std::string html = args.html_path.empty() ? "" : UnitReportHtml(identified, unit, page);
  SaveParams(identified, args.out_path);
  std::cout << "wrote " << args.out_path << "\n";
  WriteHtml(args.html_path, html);
  // A fit that did not converge or whose verdict does not accept its misfit:
  // its best point is written (its provenance says so), and the exit status
  // is the spec's numerical failure.
  const std::vector<std::string> failed = report.NotAccepted();
  for (const std::string& fit : failed) std::cout << "not accepted: " << fit << "\n";
  return failed.empty() ? kSuccess : kNumericalFailure;
}

}  // namespace

CommandRunner AddIdentifyCommand(CLI::App* app) {
  auto args = std::make_shared<IdentifyArgs>();
  app->add_option("unit", args->unit_dir, "unit directory")->required();
  app->add_option("--only", args->only,
                  "components to fit: valve, pipeline, friction (default: all)");
  app->add_option("--prior", args->prior_path, "parameter set for what is not fitted")
      ->capture_default_str();
  app->add_option("--out", args->out_path, "identified parameter set (params-v1)")
      ->required()
      ->check(InExistingDirectory);
  auto* fit = app->add_flag("--fit-u-sat", args->fit_u_sat,
                            "fit each valve branch's saturation opening u_sat (the default)");
  app->add_flag("--fix-u-sat", args->fix_u_sat, "keep the prior's u_sat instead of fitting it")
      ->excludes(fit);
  auto* refine =
      app->add_flag("--refine", args->refine,
                    "after the component fits, refine through the simulator (see --spec)");
  app->add_option("--spec", args->spec_path, "fit spec for --refine")
      ->capture_default_str()
      ->needs(refine);
  app->add_flag("--no-stick-creep", args->no_stick_creep,
                "--refine: fit the paper model's event stick only, no creep speed "
                "(effects.stick_creep.v; docs/refinement.md)")
      ->needs(refine);
  app->add_option(
         "--threads", args->threads,
         "--refine: experiments, and the friction screen's candidates, simulated in parallel")
      ->check(CLI::Range(1, 256))
      ->needs(refine);
  AddHtmlOption(app, &args->html_path);
  return [args]() { return RunIdentify(*args); };
}

}  // namespace pneumaid::cli
