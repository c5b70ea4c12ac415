// Writes a synthetic unit to a fresh temporary directory and reads it back
// through the rig-data reader, as a user's unit would be read. The
// directory is `name` plus the process id (ctest runs each test of a file as
// its own process, in parallel, and two writing one directory collide) and
// is removed once read: a Unit holds its logs in memory.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "pneumaid/io/rig_data.h"
#include "pneumaid/synth/synthetic_rig.h"

namespace pneumaid::testing {

inline Unit WriteAndReadUnit(const SyntheticUnit& unit, const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::path(::testing::TempDir()) / (name + "-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  WriteDirectoryAtomically(dir.string(), UnitFiles(unit));
  try {
    Unit read = ReadUnit(dir.string());
    std::filesystem::remove_all(dir);
    return read;
  } catch (...) {
    std::filesystem::remove_all(dir);  // a unit that does not read leaves nothing behind
    throw;
  }
}

// `unit` as a rig whose position transducer is zeroed `offset_m` off writes
// it: every logged x moved by the offset.
inline Unit WithPositionOffset(Unit unit, double offset_m) {
  for (Experiment& e : unit.experiments) {
    const auto x = e.columns.find("x");
    if (x == e.columns.end()) continue;
    for (double& value : x->second) value += offset_m;
  }
  return unit;
}

}  // namespace pneumaid::testing
