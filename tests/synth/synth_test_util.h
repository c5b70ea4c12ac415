// Writes a synthetic unit to a fresh temporary directory and reads it back
// through the rig-data reader, as a user's unit would be read.
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "pneumaid/io/rig_data.h"
#include "pneumaid/synth/synthetic_rig.h"

namespace pneumaid::testing {

inline Unit WriteAndReadUnit(const SyntheticUnit& unit, const std::string& name) {
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / name;
  std::filesystem::remove_all(dir);
  WriteDirectoryAtomically(dir.string(), UnitFiles(unit));
  Unit read = ReadUnit(dir.string());
  std::filesystem::remove_all(dir);
  return read;
}

}  // namespace pneumaid::testing
