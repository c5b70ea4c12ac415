#include <iostream>
#include <string>

#include "commands.h"
#include "pneumaid/io/files.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/report/report.h"

namespace pneumaid::cli {

CommandRunner AddReportCommand(CLI::App* app) {
  struct Args {
    std::string params_path, unit_dir, out_path;
  };
  auto args = std::make_shared<Args>();
  app->add_option("unit", args->unit_dir, "unit directory")->required();
  app->add_option("--params", args->params_path, "parameter set (params-v1)")->required();
  app->add_option("--out", args->out_path, "the report (one self-contained HTML file)")->required();
  return [args]() {
    const std::string html =
        UnitReportHtml(LoadParams(args->params_path), ReadUnit(args->unit_dir), ReportOptions{});
    WriteFileAtomically(args->out_path, html);
    std::cout << "wrote " << args->out_path << " (" << html.size() / 1024 << " KiB)\n";
    return kSuccess;
  };
}

}  // namespace pneumaid::cli
