#include <unistd.h>

#include <charconv>
#include <cstdlib>
#include <iostream>
#include <string>

#include "commands.h"
#include "pneumaid/batch/batch.h"
#include "pneumaid/io/files.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/report/report.h"

namespace pneumaid::cli {
namespace {

struct BatchArgs {
  std::string fleet_dir;
  std::string out_dir;
  int jobs = 1;
  std::string shard;  // "i/N" or "auto"
  bool resume = false, refine = false, validate = false, diagnose = false;
  std::string effects;  // --diagnose's candidates, "a,b,..."
  double timeout_s = 0;
  std::string prior_path = DefaultConfig("paper.yaml");
  std::string spec_path = DefaultConfig("fit-default.yaml");
  std::string html_path;
};

Shard ParseShard(const std::string& text) {
  Shard shard;
  if (text.empty()) return shard;
  std::string why;
  if (text == "auto") {
    if (!ShardFromEnvironment([](const char* name) { return std::getenv(name); }, &shard, &why))
      throw InputError("--shard auto", 0, 0, why);
    return shard;
  }
  // i/N, both whole numbers and nothing else (std::from_chars: no locale).
  const std::size_t slash = text.find('/');
  long index = -1, count = 0;
  const char* begin = text.c_str();
  const bool parsed =
      slash != std::string::npos &&
      std::from_chars(begin, begin + slash, index).ptr == begin + slash &&
      std::from_chars(begin + slash + 1, begin + text.size(), count).ptr == begin + text.size();
  if (!parsed || count < 1 || index < 0 || index >= count) {
    throw InputError("--shard", 0, 0, "expected i/N with 0 <= i < N (or auto), got '" + text + "'");
  }
  shard.index = static_cast<int>(index);
  shard.count = static_cast<int>(count);
  return shard;
}

int RunBatchCommand(const BatchArgs& args) {
  // The page may replace neither a unit's file nor a result it reads.
  RefuseOverwritingInputs({args.html_path}, {args.fleet_dir, args.out_dir});
  RefuseDirectoryInAUnit(args.out_dir);
  BatchOptions options;
  options.prior = LoadParams(args.prior_path);
  options.identify.tool_version = PNEUMAID_VERSION;
  options.identify.date = UtcNow();
  options.refine = args.refine;
  if (args.refine) options.spec = LoadFitSpec(args.spec_path);
  options.validate = args.validate;
  options.diagnose = args.diagnose;
  options.diagnosis.effects = SplitList(args.effects);
  if (!args.effects.empty() && !args.diagnose)
    throw InputError("--effects", 0, 0, "names diagnose's candidates: give --diagnose too");
  options.jobs = args.jobs;
  options.shard = ParseShard(args.shard);
  options.resume = args.resume;
  options.timeout_per_unit_s = args.timeout_s;
  const bool terminal = ::isatty(STDERR_FILENO) != 0;
  options.progress = [terminal](const std::string& line) {
    // A terminal gets one line that updates; a log file plain lines.
    std::cerr << (terminal ? "\r\033[K" : "") << line << (terminal ? "" : "\n") << std::flush;
  };
  const BatchSummary summary = NamingFlag("batch options", "diagnosis.effects", "--effects", [&] {
    return RunBatch(args.fleet_dir, args.out_dir, options);
  });
  if (terminal) std::cerr << "\n";
  std::cout << summary.BriefReport();
  if (!args.html_path.empty()) {
    // The page of what the results directory holds now (every shard's units).
    ReportOptions page;
    page.text_report = summary.BriefReport();
    WriteHtml(args.html_path, FleetReportHtml(MergeResults({args.out_dir}), page));
  }
  return summary.failed() > 0 ? kNumericalFailure : kSuccess;
}

}  // namespace

CommandRunner AddBatchCommand(CLI::App* app) {
  auto args = std::make_shared<BatchArgs>();
  app->add_option("fleet", args->fleet_dir, "fleet directory (one unit directory per unit)")
      ->required();
  app->add_option("--out", args->out_dir, "results directory")->required();
  app->add_option("-j,--jobs", args->jobs, "worker threads (busy threads in total)")
      ->check(CLI::Range(1, 1024));
  app->add_option("--shard", args->shard,
                  "i/N: this process's share of the fleet (by unit name); auto: from the Slurm "
                  "array, Open MPI or PMI variables");
  app->add_flag("--resume", args->resume,
                "skip units whose result is complete and whose inputs and options are unchanged");
  auto* refine = app->add_flag("--refine", args->refine, "refine each identified set (see --spec)");
  app->add_flag("--validate", args->validate, "validate each final set on its validation runs");
  app->add_flag("--diagnose", args->diagnose, "diagnose each final set (one effect at most)");
  app->add_option("--effects", args->effects,
                  "--diagnose's candidate effects, comma-separated (default: every one the set "
                  "lacks)");
  app->add_option("--timeout-per-unit", args->timeout_s,
                  "seconds after which a unit's work stops (0: none)")
      ->check(CLI::NonNegativeNumber);
  app->add_option("--prior", args->prior_path, "identify's prior")->capture_default_str();
  app->add_option("--spec", args->spec_path, "fit spec for --refine")
      ->capture_default_str()
      ->needs(refine);
  AddHtmlOption(app, &args->html_path);
  return [args]() { return RunBatchCommand(*args); };
}

CommandRunner AddMergeCommand(CLI::App* app) {
  auto dirs = std::make_shared<std::vector<std::string>>();
  auto out = std::make_shared<std::string>();
  auto html = std::make_shared<std::string>();
  app->add_option("results", *dirs, "results directories (of batch runs or shards)")->required();
  app->add_option("--out", *out, "write fleet-summary.csv and fleet-summary.md here")
      ->check(DirectoryToWrite);
  AddHtmlOption(app, html.get());
  return [dirs, out, html]() {
    const std::string csv = out->empty() ? "" : *out + "/fleet-summary.csv";
    const std::string markdown = out->empty() ? "" : *out + "/fleet-summary.md";
    RefuseOverwritingInputs({csv, markdown, *html}, *dirs);
    const FleetSummary summary = MergeResults(*dirs);
    const std::string page = html->empty() ? "" : FleetReportHtml(summary, ReportOptions{});
    if (out->empty()) {
      std::cout << summary.Markdown();
    } else {
      MakeOutputDirectory(*out);
      WriteFileAtomically(csv, summary.Csv());
      WriteFileAtomically(markdown, summary.Markdown());
      std::cout << summary.Markdown().substr(0, summary.Markdown().find("## Units")) << "wrote "
                << *out << "/fleet-summary.csv and fleet-summary.md\n";
    }
    WriteHtml(*html, page);
    return kSuccess;
  };
}

}  // namespace pneumaid::cli
