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
  return InExistingDirectory(directory);
}

void RefuseOverwritingInputs(const std::vector<std::string>& outputs,
                             const std::vector<std::string>& inputs) {
  namespace fs = std::filesystem;
  // Every input file: a unit directory's manifest and logs (not a set written
  // beside them, which a rerun replaces), any other directory's files.
  std::vector<fs::path> files;
  for (const std::string& input : inputs) {
    std::error_code error;
    if (input.empty()) continue;
    if (fs::is_directory(input, error)) {
      const bool unit = fs::exists(fs::path(input) / "unit.yaml", error);
      for (const auto& entry : fs::directory_iterator(input, error)) {
        const bool read =
            !unit || entry.path().filename() == "unit.yaml" || entry.path().extension() == ".csv";
        if (entry.is_regular_file(error) && read) files.push_back(entry.path());
      }
    } else if (fs::exists(input, error)) {
      files.push_back(input);
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
