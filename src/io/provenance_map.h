// Provenance (pneumaid/io/provenance.h) as a yaml-cpp mapping, for the
// library's writers of an entry.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>

namespace pneumaid {

// The provenance as a YAML mapping: what it carried (text that is not a
// mapping is kept under `given`), or an empty one.
YAML::Node ProvenanceMap(const std::string& provenance);

// Whether a YAML 1.1 or 1.2 reader (PyYAML, the ROS 2 parameter files)
// would resolve the plain scalar `text` to something other than a string:
// anything that starts like a number (a unit "0001", a date), and the words
// that mean a bool or null (ASCII, whatever the process's locale).
bool ReadAsOtherThanText(const std::string& text);

// Writes a provenance node to `out`: the values of its text keys (unit,
// file, sha256, date, ...; `text` for a node under one) and any key that
// another reader would take for other than text double-quoted, the rest as
// yaml-cpp writes it. The one way the library writes provenance.
void EmitProvenanceNode(const YAML::Node& node, bool text, YAML::Emitter* out);

// A provenance mapping as text, in flow style (values quoted by the emitter
// where they need it): the one way the library writes provenance. `what`
// names it in the (logic) error of a yaml-cpp writer failure.
std::string EmitProvenance(const YAML::Node& root, const std::string& what = "provenance");

// `provenance` with the entry `key` set to `entry` (replacing any earlier
// one: a mapping has one key of a name), emitted in flow style (values
// quoted by the emitter where they need it).
std::string WithProvenanceEntry(const std::string& provenance, const std::string& key,
                                const YAML::Node& entry);

}  // namespace pneumaid
