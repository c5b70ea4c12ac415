// params-v1 (`pneumaid-params/1`) load and save. See docs/params-format.md.
#pragma once

#include <string>

#include "pneumaid/model/parameters.h"

namespace pneumaid {

inline constexpr const char* kParamsFormat = "pneumaid-params/1";

// Parses a parameter set; `source_name` is used in error messages. Throws
// InputError naming the line and column of the first problem: YAML syntax,
// unknown or missing keys, wrong types, non-physical values.
Parameters ParamsFromYaml(const std::string& text, const std::string& source_name);

// Reads and parses a parameter file (throws InputError).
Parameters LoadParams(const std::string& path);

// The params-v1 document for `params`; every double written so that it reads
// back bit for bit.
std::string ParamsToYaml(const Parameters& params);

// Validates, then writes atomically (throws InputError on an invalid set).
void SaveParams(const Parameters& params, const std::string& path);

// Shortest decimal text that reads back to exactly `value`.
std::string FormatDouble(double value);

}  // namespace pneumaid
