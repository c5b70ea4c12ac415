#include <iostream>
#include <string>

#include "commands.h"
#include "pneumaid/io/log_notes.h"

namespace pneumaid::cli {

Unit ReadUnitSayingWhatItAssumed(const std::string& directory) {
  Unit unit = ReadUnit(directory);
  // The format's promise: the tool says which rig defaults it used, and
  // reports extra columns once as ignored (check lists them too).
  if (!unit.manifest.defaults_used.empty()) {
    std::cerr << "note: " << unit.manifest_path() << ": rig defaults used:";
    for (const std::string& path : unit.manifest.defaults_used) std::cerr << " " << path;
    std::cerr << "\n";
  }
  // What the logs contradict or repeat of the manifest (check lists them too).
  for (const std::string& note : ManifestNotes(unit))
    std::cerr << "note: " << unit.manifest_path() << ": " << note << "\n";
  for (const Experiment& e : unit.experiments) {
    if (e.ignored_columns.empty()) continue;
    std::cerr << "note: " << e.path << ": ignored columns:";
    for (const std::string& name : e.ignored_columns) std::cerr << " " << name;
    std::cerr << "\n";
  }
  return unit;
}

void NoteASetOfAnotherUnit(const std::string& params_path, const Parameters& params,
                           const Unit& unit) {
  if (params.unit.empty() || params.unit == unit.manifest.unit) return;
  std::cerr << "note: " << params_path << " names unit " << params.unit << "; the logs are unit "
            << unit.manifest.unit << "\n";
}

}  // namespace pneumaid::cli
