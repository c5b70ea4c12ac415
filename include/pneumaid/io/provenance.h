// A parameter set's provenance (params-v1 `provenance`, docs/params-format.md):
// a mapping to which each tool that produced the set adds its entry
// (`identify`, `refine`, ...). Text that is not a mapping is read as one
// entry `given`. The one home for reading it and adding to it.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace pneumaid {

// Whether the provenance has a top-level entry `key` (`refine`: the set was
// refined).
bool HasProvenanceEntry(const std::string& provenance, const std::string& key);

// The strings of the sequence `key`.`field` (`refine`.`at_bound`), empty
// when there is none.
std::vector<std::string> ProvenanceList(const std::string& provenance, const std::string& key,
                                        const std::string& field);

// The string values of the mapping `key`.`field` (`refine`.`held`: path ->
// why), or of the top-level mapping `field` when `key` is empty (identify's
// `held`); empty when there is none.
std::map<std::string, std::string> ProvenanceStrings(const std::string& provenance,
                                                     const std::string& key,
                                                     const std::string& field);

// The provenance as one JSON object (text that is not a mapping as
// {"given": text}); plain YAML numbers, booleans and null as JSON's own, every
// other scalar a string.
std::string ProvenanceJson(const std::string& provenance);

}  // namespace pneumaid
