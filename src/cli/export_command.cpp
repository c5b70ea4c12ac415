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
  app->add_option("--node", args->node, "ROS 2 node name")->capture_default_str();
  return [args]() {
    ExportOptions options;
    if (!ParseExportFormat(args->format, &options.format)) {
      throw InputError("--format", 0, 0,
                       "expected ros2, c-header, matlab or json, got '" + args->format + "'");
    }
    options.ros2_node = args->node;
    const std::string text = ExportParameters(LoadParams(args->params_path), options);
    if (args->out_path.empty()) {
      std::cout << text;
    } else {
      WriteFileAtomically(args->out_path, text);
    }
    return kSuccess;
  };
}

}  // namespace pneumaid::cli
