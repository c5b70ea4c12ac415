// Where a command may write: checks of its output paths before it runs, so
// that a long fit does not end in "cannot write", and no output replaces one
// of the command's inputs.
#include <filesystem>
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

void RefuseOverwritingInputs(const std::vector<std::string>& outputs,
                             const std::vector<std::string>& inputs) {
  namespace fs = std::filesystem;
  // Every input file: a unit directory's manifest and logs (in its
  // subdirectories too; not a set written beside them, which a rerun
  // replaces). Other directories are named by their files.
  std::vector<fs::path> files;
  for (const std::string& input : inputs) {
    std::error_code error;
    if (input.empty()) continue;
    if (!fs::is_directory(input, error)) {
      if (fs::exists(input, error)) files.push_back(input);
      continue;
    }
    if (!fs::exists(fs::path(input) / "unit.yaml", error)) continue;
    files.push_back(fs::path(input) / "unit.yaml");
    for (fs::recursive_directory_iterator it(input, error), end; !error && it != end;
         it.increment(error)) {
      if (it->path().extension() == ".csv" && it->is_regular_file(error))
        files.push_back(it->path());
    }
  }
  for (const std::string& output : outputs) {
    std::error_code error;
    if (output.empty() || !fs::exists(output, error)) continue;
    for (const fs::path& file : files) {
      if (fs::equivalent(output, file, error)) {
        throw InputError(output, 0, 0,
                         "an output here would replace an input of this command (" + file.string() +
                             "): expected another path");
      }
    }
  }
}

}  // namespace pneumaid::cli
