// Reading input files whole, and writing output files atomically: to a
// temporary name beside the target, then renamed, so a reader never sees a
// half-written file and a failed run leaves the old file (or none) in place.
#pragma once

#include <string>

namespace pneumaid {

// Writes `contents` to `path` atomically. Throws InputError when the target
// directory cannot be written.
void WriteFileAtomically(const std::string& path, const std::string& contents);

// The whole contents of `path`; throws InputError "cannot open <what>" when it
// cannot be read.
std::string ReadTextFile(const std::string& path, const std::string& what);

}  // namespace pneumaid
