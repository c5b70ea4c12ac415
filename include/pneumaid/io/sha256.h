// SHA-256 (FIPS 180-4) of a byte string, as 64 lowercase hex digits. For the
// provenance of input files; no dependency beyond the standard library.
#pragma once

#include <string>

namespace pneumaid {

std::string Sha256Hex(const std::string& bytes);

}  // namespace pneumaid
