#include "pneumaid/io/provenance.h"

#include <cmath>
#include <regex>
#include <set>
#include <stdexcept>

#include "parse_number.h"
#include "pneumaid/io/json.h"
#include "provenance_map.h"

namespace pneumaid {

YAML::Node ProvenanceMap(const std::string& provenance) {
  YAML::Node root;
  try {
    root = YAML::Load(provenance);
  } catch (const YAML::Exception&) {
    YAML::Node kept(YAML::NodeType::Map);
    kept["given"] = provenance;
    return kept;
  }
  if (root.IsMap()) return root;
  YAML::Node kept(YAML::NodeType::Map);
  if (root.IsDefined() && !root.IsNull()) {
    kept["given"] = root;
  } else if (provenance.find_first_not_of(" \t\r\n") != std::string::npos) {
    kept["given"] = provenance;  // text YAML reads as null ("~", "null"): kept as written
  }
  return kept;
}

namespace {

// Keys whose values are text whatever they look like: yaml-cpp writes a
// string unquoted, so a unit "12345" or a file "007" would read as numbers
// (and `held` maps paths to reasons).
bool IsTextKey(const std::string& key) {
  static const std::set<std::string> kText = {"unit",   "unit_directory", "tool",   "date",
                                              "file",   "sha256",         "status", "given",
                                              "source", "held",           "verdict"};
  return kText.count(key) > 0;
}

}  // namespace

bool ReadAsOtherThanText(const std::string& text) {
  if (text.empty()) return true;
  const char first = text.front();
  if ((first >= '0' && first <= '9') || first == '.' || first == '-' || first == '+') return true;
  std::string lower;
  for (const char c : text) lower += (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
  for (const char* word : {"y", "n", "yes", "no", "on", "off", "true", "false", "null", "~"}) {
    if (lower == word) return true;
  }
  return false;
}

void EmitProvenanceNode(const YAML::Node& node, bool text, YAML::Emitter* out) {
  // A collection keeps the style it was read or built with (provenance is
  // flow style inside a block-style parameter file).
  if ((node.IsMap() || node.IsSequence()) && node.Style() == YAML::EmitterStyle::Flow)
    *out << YAML::Flow;
  if (node.IsMap()) {
    *out << YAML::BeginMap;
    for (const auto& item : node) {
      const std::string key = item.first.Scalar();
      *out << YAML::Key;
      if (ReadAsOtherThanText(key)) *out << YAML::DoubleQuoted;
      *out << key << YAML::Value;
      EmitProvenanceNode(item.second, text || IsTextKey(key), out);
    }
    *out << YAML::EndMap;
  } else if (node.IsSequence()) {
    *out << YAML::BeginSeq;
    for (const auto& item : node) EmitProvenanceNode(item, text, out);
    *out << YAML::EndSeq;
  } else if (node.IsScalar()) {
    if (text && ReadAsOtherThanText(node.Scalar())) *out << YAML::DoubleQuoted;
    *out << node.Scalar();
  } else {
    *out << YAML::Null;
  }
}

std::string EmitProvenance(const YAML::Node& root, const std::string& what) {
  YAML::Emitter out;
  out.SetMapFormat(YAML::Flow);
  out.SetSeqFormat(YAML::Flow);
  EmitProvenanceNode(root, false, &out);
  // yaml-cpp reports an emitter error in its state, not by throwing.
  if (!out.good()) throw std::logic_error(what + ": " + out.GetLastError());
  return out.c_str();
}

std::string WithProvenanceEntry(const std::string& provenance, const std::string& key,
                                const YAML::Node& entry) {
  YAML::Node root = ProvenanceMap(provenance);
  root[key] = entry;
  return EmitProvenance(root, "provenance entry " + key);
}

bool HasProvenanceEntry(const std::string& provenance, const std::string& key) {
  return ProvenanceMap(provenance)[key].IsDefined();
}

namespace {

// The node `key`.`field` of the provenance (the top level's `field` when
// `key` is empty); undefined when there is none. Not const: a const node's
// missing key is an invalid node, which throws when asked anything; a
// mutable node's is an undefined one.
YAML::Node Field(const std::string& provenance, const std::string& key, const std::string& field) {
  YAML::Node root = ProvenanceMap(provenance);
  YAML::Node entry = key.empty() ? root : root[key];
  if (!entry.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
  return entry[field];
}

// A node as JSON: mappings as objects, sequences as arrays; a plain scalar
// in JSON's spelling of a finite number, or true, false or null, as that
// (unless `text`); every other scalar as a string.
void AppendJson(const YAML::Node& node, bool text, std::string* out) {
  if (node.IsMap()) {
    *out += '{';
    bool first = true;
    for (const auto& item : node) {
      *out += first ? "" : ", ";
      *out += JsonString(item.first.Scalar()) + ": ";
      AppendJson(item.second, text || IsTextKey(item.first.Scalar()), out);
      first = false;
    }
    *out += '}';
  } else if (node.IsSequence()) {
    *out += '[';
    for (size_t i = 0; i < node.size(); ++i) {
      *out += i == 0 ? "" : ", ";
      AppendJson(node[i], text, out);
    }
    *out += ']';
  } else if (node.IsScalar()) {
    static const std::regex number(
        R"(-?(0|[1-9][0-9]{0,300})(\.[0-9]{1,300})?([eE][-+]?[0-9]{1,4})?)");
    const std::string& scalar = node.Scalar();
    const bool plain = !text && node.Tag() == "?";
    double value = 0;
    const char* end = scalar.c_str() + scalar.size();
    if (plain && (scalar == "true" || scalar == "false" || scalar == "null")) {
      *out += scalar;
    } else if (plain && std::regex_match(scalar, number) &&
               internal::ParseNumber(scalar.c_str(), end, &value) == end && std::isfinite(value)) {
      *out += scalar;
    } else {
      *out += JsonString(scalar);
    }
  } else {
    *out += "null";
  }
}

}  // namespace

std::string ProvenanceJson(const std::string& provenance) {
  std::string out;
  AppendJson(ProvenanceMap(provenance), false, &out);
  return out;
}

std::vector<std::string> ProvenanceList(const std::string& provenance, const std::string& key,
                                        const std::string& field) {
  std::vector<std::string> items;
  const YAML::Node list = Field(provenance, key, field);
  if (!list.IsSequence()) return items;
  for (const YAML::Node& item : list) {
    if (item.IsScalar()) items.push_back(item.Scalar());
  }
  return items;
}

std::map<std::string, std::string> ProvenanceStrings(const std::string& provenance,
                                                     const std::string& key,
                                                     const std::string& field) {
  std::map<std::string, std::string> items;
  const YAML::Node mapping = Field(provenance, key, field);
  if (!mapping.IsMap()) return items;
  for (const auto& item : mapping) {
    if (item.first.IsScalar() && item.second.IsScalar())
      items[item.first.Scalar()] = item.second.Scalar();
  }
  return items;
}

}  // namespace pneumaid
