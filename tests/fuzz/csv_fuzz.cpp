// libFuzzer target: the CSV dialect and the conversion of a stroke log to SI.
// Any input must either parse or throw InputError; nothing else (no crash,
// leak or sanitizer report). Build with scripts/fuzz.sh.
#include <cstddef>
#include <cstdint>
#include <string>

#include "pneumaid/io/csv_table.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/rig_data.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    pneumaid::ParseCsv(text, "fuzz.csv");
  } catch (const pneumaid::InputError&) {
  }
  pneumaid::Manifest manifest;
  pneumaid::ExperimentEntry entry;
  entry.kind = size % 2 ? pneumaid::ExperimentKind::kStroke : pneumaid::ExperimentKind::kValve;
  manifest.rig.position_origin =
      size % 3 ? pneumaid::PositionOrigin::kRetracted : pneumaid::PositionOrigin::kMid;
  try {
    pneumaid::ParseExperiment(text, "fuzz.csv", entry, manifest);
  } catch (const pneumaid::InputError&) {
  }
  return 0;
}
