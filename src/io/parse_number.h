// Locale-independent parsing of a decimal number for every reader of
// pneumaid: std::from_chars reads the C locale's format whatever the host
// program's setlocale says (strtod would read "0,5" in a German locale). A
// leading '+' is accepted, as in strtod.
#pragma once

#include <algorithm>
#include <charconv>
#include <system_error>

namespace pneumaid::internal {

// Parses a number at the start of [begin, end) into *value; returns where the
// number ends, or nullptr when there is none.
inline const char* ParseNumber(const char* begin, const char* end, double* value) {
  if (begin != end && *begin == '+') {
    ++begin;
    if (begin != end && (*begin == '+' || *begin == '-')) return nullptr;
  }
  const auto [stop, status] = std::from_chars(begin, end, *value);
  if (status == std::errc::result_out_of_range) {
    // A finite number below the smallest double ("1e-400") is read as zero,
    // as strtod reads it; one above the largest is no finite number.
    const char* exponent = std::find_if(begin, stop, [](char c) { return c == 'e' || c == 'E'; });
    if (exponent + 1 < stop && exponent[1] == '-') {
      *value = *begin == '-' ? -0.0 : 0.0;
      return stop;
    }
    return nullptr;
  }
  return status == std::errc() ? stop : nullptr;
}

}  // namespace pneumaid::internal
