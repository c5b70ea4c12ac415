// The `pneumaid` subcommands. Each registers its options on the app and
// returns the function that runs it; that function returns the exit status.
#pragma once

#include <CLI/CLI.hpp>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "pneumaid/ident/refine.h"
#include "pneumaid/io/input_error.h"

namespace pneumaid::cli {

// Exit statuses of every command (params spec).
enum ExitStatus : int {
  kSuccess = 0,
  kUnexpected = 1,
  kBadInput = 2,
  kNumericalFailure = 3,
  kQualityMissed = 4,
};

using CommandRunner = std::function<int()>;

// "KEY=NUMBER" items of a repeatable option -> map. `expected` describes the
// form in the error message; `key_allowed` (may be empty) vets each key.
std::map<std::string, double> ParseAssignments(
    const std::vector<std::string>& items, const std::string& option, const std::string& expected,
    const std::function<bool(const std::string&)>& key_allowed = {});

// The library's options name their fields in messages ("ros2_node: expected
// ..."); the CLI names the flag that sets each. Throws InputError(flag, rest
// of the message) when `message` starts with one of `flags`' fields
// ("ros2_node: " -> "--node"); returns when it starts with none.
void ThrowNamingTheFlag(const std::string& message,
                        const std::vector<std::pair<std::string, std::string>>& flags);

// "a,b,..." -> {"a", "b", ...}; empty items dropped (--effects).
std::vector<std::string> SplitList(const std::string& text);

// Runs `work`; an InputError the library raises about one field of its
// options ("effects: unknown ..." from "diagnose options") is raised again
// naming the flag the user typed instead (`flag`: "--effects").
template <typename Work>
auto NamingFlag(const std::string& options, const std::string& field, const std::string& flag,
                Work work) -> decltype(work()) {
  try {
    return work();
  } catch (const InputError& error) {
    const std::string object = field + ": ";
    if (error.file() != options || error.message().compare(0, object.size(), object)) throw;
    throw InputError(flag, 0, 0, error.message().substr(object.size()));
  }
}

// Prints a refinement's report and writes its parameter set (and, with
// `html_path`, the unit's report of it, `text_before` heading its text); the
// exit status says whether it converged (refine, identify --refine). The
// result is one of RefineOptions::ForIdentify(): where the model does not
// explain the runs, the set written is the start.
int ReportAndSave(const RefineResult& result, const Unit& unit, const std::string& out_path,
                  const std::string& html_path, const std::string& text_before = "");

// --html FILE on a command: one self-contained HTML report (report.h).
void AddHtmlOption(CLI::App* app, std::string* path);
// An output file's check before the command runs (CLI11's check: "" or why):
// its directory must exist, so a long fit does not end in "cannot write".
std::string InExistingDirectory(const std::string& file);
// An output directory's check: an existing directory, or one that can be
// made in an existing one (not a file).
std::string DirectoryToWrite(const std::string& directory);
// Makes the output directory DirectoryToWrite accepted (InputError naming it
// when it cannot be made), once everything is computed.
void MakeOutputDirectory(const std::string& directory);
// InputError naming the first of `outputs` that is one of `inputs` (files,
// or directories whose files are inputs: a unit directory's manifest and
// logs; a fleet's units; every file of a results directory), or that another
// of `outputs` names already, before the command writes anything.
void RefuseOverwritingInputs(const std::vector<std::string>& outputs,
                             const std::vector<std::string>& inputs);
// InputError when `directory` (an output directory) lies in a unit directory.
void RefuseDirectoryInAUnit(const std::string& directory);
// The files of a diagnose output directory that `report --diagnose` reads
// back (diagnose writes them, with its CSVs).
inline constexpr const char* kDiagnoseOutputFiles[] = {"report.md", "params.yaml", "report.json"};
// Writes the page atomically and says so; nothing for an empty path.
void WriteHtml(const std::string& path, const std::string& html);

// A shipped config (paper.yaml, fit-default.yaml): an installation's, beside
// the binary (<prefix>/share/pneumaid/configs), else this source tree's.
std::string DefaultConfig(const std::string& name);

// ReadUnit, then on stderr the rig defaults the manifest left to the format
// and the columns of each log that are ignored (the format's promise that
// the tool says so; `check` lists them with the rest).
Unit ReadUnitSayingWhatItAssumed(const std::string& directory);
// On stderr, when the set read from `params_path` names another unit than
// `unit`'s logs (a fleet's sets mixed up; the paper's set says "paper").
void NoteASetOfAnotherUnit(const std::string& params_path, const Parameters& params,
                           const Unit& unit);

// The current time, UTC, ISO 8601 (for provenance).
std::string UtcNow();

CommandRunner AddSimulateCommand(CLI::App* app);
CommandRunner AddSynthCommand(CLI::App* app);
CommandRunner AddCheckCommand(CLI::App* app);
CommandRunner AddValidateCommand(CLI::App* app);
CommandRunner AddIdentifyCommand(CLI::App* app);
CommandRunner AddRefineCommand(CLI::App* app);
CommandRunner AddDiagnoseCommand(CLI::App* app);
CommandRunner AddBatchCommand(CLI::App* app);
CommandRunner AddMergeCommand(CLI::App* app);
CommandRunner AddExportCommand(CLI::App* app);
CommandRunner AddReportCommand(CLI::App* app);

}  // namespace pneumaid::cli
