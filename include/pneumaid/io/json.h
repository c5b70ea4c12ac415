// Writing JSON by hand, for the machine-readable reports: numbers in the C
// locale (null for non-finite values), strings escaped.
#pragma once

#include <string>

namespace pneumaid {

// 9 significant digits (%.9g-like, never a locale's decimal comma); "null"
// for NaN and infinities.
std::string JsonNumber(double value);

// `digits` significant digits, %g-like, never a locale's decimal comma: the
// one way numbers are written into data files (CSV, JSON).
std::string FormatSignificant(double value, int digits);

// A quoted, escaped JSON string.
std::string JsonString(const std::string& text);

}  // namespace pneumaid
