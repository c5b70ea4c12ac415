#include <iostream>
#include <string>

#include "commands.h"
#include "pneumaid/io/export.h"
#include "pneumaid/io/files.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"

namespace pneumaid::cli {

CommandRunner AddExportCommand(CLI::App* app) {
  struct Args {
    std::string params_path, format, out_path, node = "pneumaid";
  };
  auto args = std::make_shared<Args>();
  app->add_option("--params", args->params_path, "parameter set (params-v1)")->required();
  app->add_option("--format", args->format, "ros2, c-header, matlab or json")->required();
  app->add_option("--out", args->out_path, "output file (default: stdout)")
      ->check(InExistingDirectory);
  CLI::Option* node = app->add_option("--node", args->node, "ROS 2 node name (--format ros2)")
                          ->capture_default_str();
  return [args, node]() {
    RefuseOverwritingInputs({args->out_path}, {args->params_path});
    ExportOptions options;
    if (!ParseExportFormat(args->format, &options.format)) {
      throw InputError("--format", 0, 0,
                       "expected ros2, c-header, matlab or json, got '" + args->format + "'");
    }
    if (node->count() > 0 && options.format != ExportFormat::kRos2) {
      throw InputError("--node", 0, 0,
                       "names the ROS 2 node, and --format " + args->format + " has none");
    }
    options.ros2_node = args->node;
    const Parameters params = LoadParams(args->params_path);
    std::string text;
    try {
      text = ExportParameters(params, options);
    } catch (const InputError& error) {
      ThrowNamingTheFlag(error.message(), {{"ros2_node: ", "--node"}});
      throw;
    }
    if (args->out_path.empty()) {
      std::cout << text;
    } else {
      WriteFileAtomically(args->out_path, text);
    }
    return kSuccess;
  };
}

}  // namespace pneumaid::cli
