// Writing JSON and CSV by hand, for the machine-readable reports: numbers
// without the locale (null for non-finite values), strings escaped.
#pragma once

#include <string>

namespace pneumaid {

// 9 significant digits (%.9g-like, never a locale's decimal comma); "null"
// for NaN and infinities.
std::string JsonNumber(double value);

// `digits` significant digits, %g-like, never a locale's decimal comma: the
// one way numbers are written into data files (CSV, JSON).
std::string FormatSignificant(double value, int digits);

// A CSV field: as is, or quoted with inner quotes doubled when it holds a
// comma, a quote or a line break (a line break becomes a space).
std::string CsvField(const std::string& text);

// A quoted, escaped JSON string ('<' as \u003c, so it is safe inside a
// <script> element too).
std::string JsonString(const std::string& text);

}  // namespace pneumaid
