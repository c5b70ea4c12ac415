// Reading input files whole, and writing output files atomically: to a
// temporary name beside the target, then renamed, so a reader never sees a
// half-written file and a failed run leaves the old file (or none) in place.
#pragma once

#include <map>
#include <string>

namespace pneumaid {

// A name beside `target` for writing it first: the process id and 64 random
// bits, so that threads and processes writing one target never share it.
std::string UniqueTemporaryName(const std::string& target);

// Writes `contents` to `path` atomically. Throws InputError when the target
// directory cannot be written.
void WriteFileAtomically(const std::string& path, const std::string& contents);

// Writes `files` (name -> contents) as the directory `directory`, replacing
// any directory of that name: written under a unique temporary name, then
// renamed into place (an old one renamed away first, then removed), so a
// reader or a killed run sees the old directory, the new one, or none,
// never a part of one. Throws InputError when it cannot, std::logic_error
// when a name is not a file of its own inside the directory (absolute, "..",
// or the same file as another name).
void ReplaceDirectoryAtomically(const std::string& directory,
                                const std::map<std::string, std::string>& files);

// A log's experiment id as one file-name component for the files written
// per run (`<id>-validation.csv`): ASCII letters, digits, '_', '-' and '.'
// and the bytes of UTF-8 characters as they are, every other byte (and a
// leading '.') as %XX, so that an id such as "../x" or "a/b" names a file
// inside the output directory and two ids never share one (the format puts
// no rule on ids but their uniqueness; on a case-insensitive file system
// "Step-1" and "step-1" still would).
std::string FileNameOfId(const std::string& id);

// The whole contents of `path`; throws InputError "cannot open <what>" when it
// cannot be read.
std::string ReadTextFile(const std::string& path, const std::string& what);

}  // namespace pneumaid
