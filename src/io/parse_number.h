// Locale-independent parsing of a decimal number for every reader of
// pneumaid: std::from_chars reads the C locale's format whatever the host
// program's setlocale says (strtod would read "0,5" in a German locale). A
// leading '+' is accepted, as in strtod.
#pragma once

#include <algorithm>
#include <charconv>
#include <system_error>

namespace pneumaid::internal {

// The decimal exponent of the first significant digit of the number in
// [begin, stop) as std::from_chars reads it ("1e-400": -400; "0.05": -2;
// "120": 2); 0 for a number without one (zero).
inline long DecimalExponent(const char* begin, const char* stop) {
  const char* p = begin;
  if (p != stop && *p == '-') ++p;
  bool significant = false;  // a nonzero digit seen
  bool after_point = false;
  long position = 0;  // of the first significant digit: 0 is the units
  for (; p != stop && *p != 'e' && *p != 'E'; ++p) {
    if (*p == '.') {
      after_point = true;
    } else if (after_point) {
      if (!significant) --position;
      significant = significant || *p != '0';
    } else if (significant || *p != '0') {
      if (significant) ++position;
      significant = true;
    }
  }
  if (!significant) return 0;
  long exponent = 0;
  if (p != stop) {
    ++p;  // 'e'
    const bool negative = p != stop && *p == '-';
    if (p != stop && (*p == '-' || *p == '+')) ++p;
    for (; p != stop; ++p) exponent = std::min(exponent * 10 + (*p - '0'), 100000000L);
    if (negative) exponent = -exponent;
  }
  return position + exponent;
}

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
    // as strtod reads it; one above the largest is no finite number. Which
    // it is: the decimal exponent of its first significant digit.
    return DecimalExponent(begin, stop) < 0 ? (*value = *begin == '-' ? -0.0 : 0.0, stop) : nullptr;
  }
  return status == std::errc() ? stop : nullptr;
}

}  // namespace pneumaid::internal
