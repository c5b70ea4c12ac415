// Where a command may write: checks of its output paths before it runs, so
// that a long fit does not end in "cannot write", and no output replaces one
// of the command's inputs.
#include <filesystem>
#include <set>
#include <string>
#include <vector>

#include "commands.h"
#include "pneumaid/io/input_error.h"

namespace pneumaid::cli {

std::string InExistingDirectory(const std::string& file) {
  const std::filesystem::path parent = std::filesystem::path(file).parent_path();
  std::error_code error;
  if (std::filesystem::is_directory(file, error)) return file + " is a directory, not a file";
  if (parent.empty() || std::filesystem::is_directory(parent, error)) return "";
  return "the directory " + parent.string() + " does not exist";
}

std::string DirectoryToWrite(const std::string& directory) {
  std::error_code error;
  if (std::filesystem::is_directory(directory, error)) return "";
  if (std::filesystem::exists(directory, error))
    return directory + " exists and is not a directory";
  std::filesystem::path named(directory);
  if (!named.has_filename()) named = named.parent_path();  // "new/" names "new"
  return InExistingDirectory(named.string());
}

void MakeOutputDirectory(const std::string& directory) {
  std::error_code error;
  std::filesystem::create_directories(directory, error);
  if (error) throw InputError(directory, 0, 0, "cannot create: " + error.message());
}

namespace {

// The files an input names: a file itself; a unit directory's manifest and
// logs (in its subdirectories too; not a set written beside them, which a
// rerun replaces); a unit's batch result (a directory with params.yaml and
// stamp.txt) every file in it; any other directory (a fleet, a results
// directory) the units and results in it and the summaries merge reads
// (summary*.csv, failures*.csv), not a page or a merged summary written
// there before. `visited` keeps a directory linked into itself from being
// walked again.
void AddInputFiles(const std::filesystem::path& input, std::vector<std::filesystem::path>* files,
                   std::set<std::filesystem::path>* visited) {
  namespace fs = std::filesystem;
  std::error_code error;
  if (!fs::is_directory(input, error)) {
    if (fs::exists(input, error)) files->push_back(input);
    return;
  }
  if (!visited->insert(fs::canonical(input, error)).second || error) return;
  if (fs::exists(input / "unit.yaml", error)) {
    files->push_back(input / "unit.yaml");
    for (fs::recursive_directory_iterator it(input, error), end; !error && it != end;
         it.increment(error)) {
      if (it->path().extension() == ".csv" && it->is_regular_file(error))
        files->push_back(it->path());
    }
    return;
  }
  const bool result =
      fs::exists(input / "params.yaml", error) && fs::exists(input / "stamp.txt", error);
  for (fs::directory_iterator it(input, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    if (it->is_directory(error)) {
      if (!result) AddInputFiles(it->path(), files, visited);
    } else if (result || ((name.rfind("summary", 0) == 0 || name.rfind("failures", 0) == 0) &&
                          it->path().extension() == ".csv")) {
      files->push_back(it->path());
    }
  }
}

// `path` as the file system would resolve it, also where it does not exist
// yet (absolute first: weakly_canonical leaves a relative path that does not
// exist as it is).
std::filesystem::path Resolved(const std::string& path) {
  std::error_code error;
  const std::filesystem::path absolute = std::filesystem::absolute(path, error);
  if (error) return std::filesystem::path(path).lexically_normal();
  const std::filesystem::path resolved = std::filesystem::weakly_canonical(absolute, error);
  return error ? absolute.lexically_normal() : resolved;
}

}  // namespace

void RefuseOverwritingInputs(const std::vector<std::string>& outputs,
                             const std::vector<std::string>& inputs) {
  namespace fs = std::filesystem;
  std::vector<fs::path> files;
  std::set<fs::path> visited;
  for (const std::string& input : inputs) {
    if (!input.empty()) AddInputFiles(input, &files, &visited);
  }
  for (std::size_t k = 0; k < outputs.size(); ++k) {
    const std::string& output = outputs[k];
    if (output.empty()) continue;
    // Two outputs of one command at one path: the second would replace the first.
    for (std::size_t j = 0; j < k; ++j) {
      if (!outputs[j].empty() && Resolved(outputs[j]) == Resolved(output)) {
        throw InputError(output, 0, 0,
                         "named for two outputs of this command (also as " + outputs[j] +
                             "): expected another path");
      }
    }
    std::error_code error;
    if (!fs::exists(output, error)) continue;
    for (const fs::path& file : files) {
      if (fs::equivalent(output, file, error)) {
        throw InputError(output, 0, 0,
                         "an output here would replace an input of this command (" + file.string() +
                             "): expected another path");
      }
    }
  }
}

void RefuseDirectoryInAUnit(const std::string& directory) {
  namespace fs = std::filesystem;
  std::error_code error;
  for (fs::path at = Resolved(directory); !at.empty(); at = at.parent_path()) {
    if (fs::exists(at / "unit.yaml", error)) {
      throw InputError(directory, 0, 0,
                       "inside the unit directory " + at.string() +
                           ", whose logs it would mix with results: expected a directory outside "
                           "any unit");
    }
    if (at == at.parent_path()) break;
  }
}

}  // namespace pneumaid::cli
