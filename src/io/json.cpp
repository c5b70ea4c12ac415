#include "pneumaid/io/json.h"

#include <charconv>
#include <cmath>
#include <cstdio>

namespace pneumaid {

std::string FormatSignificant(double value, int digits) {
  char buffer[48];
  // to_chars: never the locale's decimal comma (snprintf would take a host
  // program's setlocale).
  const auto result =
      std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::general, digits);
  return std::string(buffer, result.ptr);
}

std::string JsonNumber(double value) {
  return std::isfinite(value) ? FormatSignificant(value, 9) : "null";
}

std::string JsonString(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '<') {
      out += "\\u003c";
      continue;
    }
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof(escaped), "\\u%04x", c);
      out += escaped;
      continue;
    }
    out += c;
  }
  return out + "\"";
}

std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += (c == '\n' || c == '\r') ? ' ' : c;
  }
  return out + "\"";
}

}  // namespace pneumaid
