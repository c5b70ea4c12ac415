// The bundled fleet (datasets/fleet) identified by a batch, for the fleet
// page's test and benchmark.
#pragma once

#include <filesystem>
#include <string>

#include "pneumaid/batch/batch.h"
#include "pneumaid/io/params_yaml.h"

namespace pneumaid::testing {

// Runs `batch` over datasets/fleet (prior configs/paper.yaml, 2 jobs) into
// `results`, removed first; returns its path.
inline std::string IdentifyBundledFleet(const std::filesystem::path& results,
                                        const std::string& tool_version) {
  const std::string source = PNEUMAID_SOURCE_DIR;
  std::filesystem::remove_all(results);
  BatchOptions options;
  options.prior = LoadParams(source + "/configs/paper.yaml");
  options.identify.tool_version = tool_version;
  options.jobs = 2;
  RunBatch(source + "/datasets/fleet", results.string(), options);
  return results.string();
}

}  // namespace pneumaid::testing
