#include "pneumaid/io/files.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>

#include "pneumaid/io/input_error.h"

namespace pneumaid {

std::string UniqueTemporaryName(const std::string& target) {
  // The process id alone collided when two threads wrote one target; 64
  // random bits per call (no shared state) make a collision negligible.
  std::random_device random;
  const std::uint64_t bits = (static_cast<std::uint64_t>(random()) << 32) ^ random();
  char suffix[40];
  std::snprintf(suffix, sizeof(suffix), ".tmp.%ld.%016llx", static_cast<long>(::getpid()),
                static_cast<unsigned long long>(bits));
  return target + suffix;
}

void WriteFileAtomically(const std::string& path, const std::string& contents) {
  const std::string temporary = UniqueTemporaryName(path);
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) {
      throw InputError(path, 0, 0, std::string("cannot write: ") + std::strerror(errno));
    }
    out << contents;
    out.flush();
    if (!out) {
      std::remove(temporary.c_str());
      throw InputError(path, 0, 0, "write failed (disk full?)");
    }
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0) {
    const int error = errno;
    std::remove(temporary.c_str());
    throw InputError(path, 0, 0, std::string("cannot rename into place: ") + std::strerror(error));
  }
}

std::string FileNameOfId(const std::string& id) {
  std::string name;
  for (size_t i = 0; i < id.size(); ++i) {
    const unsigned char c = static_cast<unsigned char>(id[i]);
    // ASCII by its ranges (isalnum follows the host's locale); bytes of
    // UTF-8 characters as they are (none is '/' or '.').
    const bool ascii_kept = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') ||
                            (c >= '0' && c <= '9') || c == '_' || c == '-' || (c == '.' && i > 0);
    if (ascii_kept || c >= 0x80) {
      name += static_cast<char>(c);
    } else {
      char escaped[4];
      std::snprintf(escaped, sizeof(escaped), "%%%02X", c);
      name += escaped;
    }
  }
  return name;
}

void ReplaceDirectoryAtomically(const std::string& directory,
                                const std::map<std::string, std::string>& files) {
  namespace fs = std::filesystem;
  std::set<fs::path> names;
  for (const auto& [name, contents] : files) {
    const fs::path relative = fs::path(name).lexically_normal();
    const bool inside = relative.is_relative() && relative.has_filename() &&
                        relative.filename() != "." &&
                        std::none_of(relative.begin(), relative.end(),
                                     [](const fs::path& part) { return part == ".."; }) &&
                        names.insert(relative).second;  // "a" and "./a" are one file
    if (!inside) {
      throw std::logic_error("ReplaceDirectoryAtomically: '" + name +
                             "' is not a path of its own inside " + directory);
    }
  }
  const fs::path target(directory);
  const fs::path temporary = UniqueTemporaryName(directory);
  std::error_code error;
  if (!fs::create_directories(temporary, error) && error) {
    throw InputError(directory, 0, 0, "cannot create a directory beside it: " + error.message());
  }
  fs::path old;
  try {
    for (const auto& [name, contents] : files) {
      const fs::path file = temporary / name;  // a name may hold a subdirectory
      fs::create_directories(file.parent_path());
      WriteFileAtomically(file.string(), contents);
    }
    if (fs::exists(target)) {
      old = UniqueTemporaryName(directory + ".old");
      fs::rename(target, old);
    }
    fs::rename(temporary, target);
  } catch (const fs::filesystem_error& failure) {
    if (!old.empty() && !fs::exists(target, error)) fs::rename(old, target, error);  // put it back
    fs::remove_all(temporary, error);
    throw InputError(directory, 0, 0, std::string("cannot move into place: ") + failure.what());
  } catch (...) {
    if (!old.empty() && !fs::exists(target, error)) fs::rename(old, target, error);
    fs::remove_all(temporary, error);
    throw;
  }
  if (!old.empty()) fs::remove_all(old, error);
}

std::string ReadTextFile(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, 0, 0, "cannot open " + what + ": " + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace pneumaid
