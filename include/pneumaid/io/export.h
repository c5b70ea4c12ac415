// Parameter sets for controller teams: a ROS 2 parameter file, a C header of
// named constants, a MATLAB script that builds a struct, JSON. Every export
// states the unit id and the set's provenance; every number is written with
// 17 significant digits (it reads back as the same double).
#pragma once

#include <string>

#include "pneumaid/model/parameters.h"

namespace pneumaid {

enum class ExportFormat { kRos2, kCHeader, kMatlab, kJson };

// "ros2", "c-header", "matlab", "json"; false for anything else.
bool ParseExportFormat(const std::string& name, ExportFormat* format);

struct ExportOptions {
  ExportFormat format = ExportFormat::kJson;
  std::string ros2_node = "pneumaid";  // the node the ROS 2 parameters belong to
};

// Every scalar parameter (params-v1 paths) and every effect parameter, with
// units and standard errors (comments where the format has no place for them).
std::string ExportParameters(const Parameters& params, const ExportOptions& options);

}  // namespace pneumaid
