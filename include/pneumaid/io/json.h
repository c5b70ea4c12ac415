// Writing JSON by hand, for the machine-readable reports: numbers in the C
// locale (null for non-finite values), strings escaped.
#pragma once

#include <string>

namespace pneumaid {

// 9 significant digits (%.9g-like, never a locale's decimal comma); "null"
// for NaN and infinities.
std::string JsonNumber(double value);

// A quoted, escaped JSON string.
std::string JsonString(const std::string& text);

}  // namespace pneumaid
