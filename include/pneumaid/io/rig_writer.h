// Writing unit directories of the rig-data format (what the synthetic rig and
// exports produce): the manifest with rig constants in the units a real rig
// sheet uses, and CSV logs with unit brackets.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "pneumaid/io/rig_data.h"

namespace pneumaid {

// One CSV log as written: header cells ("x [mm]") and columns in those units.
struct RigLog {
  ExperimentEntry entry;
  std::vector<std::string> header;
  std::vector<std::vector<double>> columns;
  std::string comment;  // '#' lines at the top
};

// unit.yaml for `manifest`: lengths in mm or cm, volumes in cm3, mass in g,
// pressures in bar, so that reading it back exercises the unit conversions.
std::string ManifestToYaml(const Manifest& manifest);

std::string RigLogToCsv(const RigLog& log);

// Writes `files` (name -> contents) into a new directory `directory`: first
// into a temporary sibling, then renamed into place. Refuses (InputError) when
// `directory` exists and is not empty, so nothing is overwritten.
void WriteDirectoryAtomically(const std::string& directory,
                              const std::map<std::string, std::string>& files);

// SI value -> the value written in `unit` (the inverse of ToSI; flows in a
// volumetric unit are divided by the air density first).
double FromSI(const std::string& unit, double value_in_si, double atmospheric_pressure_Pa,
              double air_density_kg_per_m3);

}  // namespace pneumaid
