// Output files are written to a temporary name beside the target and renamed,
// so a reader never sees a half-written file and a failed run leaves the old
// file (or none) in place.
#pragma once

#include <string>

namespace pneumaid {

// Writes `contents` to `path` atomically. Throws InputError when the target
// directory cannot be written.
void WriteFileAtomically(const std::string& path, const std::string& contents);

}  // namespace pneumaid
