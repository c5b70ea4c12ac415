// libFuzzer target: the unit.yaml manifest parser. Any input must either
// parse or throw InputError. Build with scripts/fuzz.sh.
#include <cstddef>
#include <cstdint>
#include <string>

#include "pneumaid/io/input_error.h"
#include "pneumaid/io/rig_data.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    pneumaid::ParseManifest(std::string(reinterpret_cast<const char*>(data), size), "fuzz.yaml");
  } catch (const pneumaid::InputError&) {
  }
  return 0;
}
