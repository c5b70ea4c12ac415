#include "pneumaid/io/export.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <sstream>
#include <utility>
#include <vector>

#include "pneumaid/io/input_error.h"
#include "pneumaid/io/json.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/provenance.h"
#include "pneumaid/model/effects.h"
#include "pneumaid/model/parameter_table.h"

namespace pneumaid {
namespace {

struct Entry {
  Entry(std::string path_, std::string unit_, std::string doc_, double value_ = 0,
        double standard_error_ = 0, std::string choice_ = "")
      : path(std::move(path_)),
        unit(std::move(unit_)),
        doc(std::move(doc_)),
        value(value_),
        standard_error(standard_error_),
        choice(std::move(choice_)) {}
  std::string path, unit, doc;
  double value = 0, standard_error = 0;  // 0: none known
  std::string choice;                    // a model's choice ("vertical"), else empty: a number
  std::vector<double> values;            // a list's numbers (then `value` is unused)
  bool IsList() const { return !values.empty(); }
};

// The choices of the model, which a controller needs as much as its numbers
// (gravity acts on a vertical rod only; a pipeline of model none uses no
// delta), each inserted before the first number of its section.
void InsertChoices(const Parameters& params, std::vector<Entry>* entries) {
  const Entry choices[] = {
      {"cylinder.orientation", "", "vertical: gravity acts on the rod and load", 0, 0,
       ToString(params.cylinder.orientation)},
      {"valve.model", "", "K_vp(u) a quartic per branch, q_max from u_sat", 0, 0, "kvp_poly4"},
      {"valve.branch", "", "which branch K_vp follows (hysteresis: by the opening's motion)", 0, 0,
       ToString(params.valve.branch)},
      {"pipeline.model", "", "the tube's delay of the flow (none: delta unused)", 0, 0,
       ToString(params.pipeline.model)},
      {"friction.model", "", "Stribeck friction per direction", 0, 0, "stribeck"},
  };
  for (const Entry& choice : choices) {
    const std::string section = choice.path.substr(0, choice.path.find('.') + 1);
    auto at = std::find_if(entries->begin(), entries->end(), [&section](const Entry& e) {
      return e.path.compare(0, section.size(), section) == 0;
    });
    entries->insert(at, choice);
  }
}

std::vector<Entry> Entries(const Parameters& params) {
  std::vector<Entry> entries;
  const auto error = [&params](const std::string& path) {
    const auto found = params.uncertainty.find(path);
    return found == params.uncertainty.end() ? 0.0 : found->second;
  };
  for (const ScalarParameterInfo& info : ScalarParameterTable()) {
    entries.push_back({info.path, info.unit, info.doc, info.get(params), error(info.path), ""});
  }
  for (const auto& [effect, values] : params.effects) {
    const EffectInfo* info = FindEffect(effect);
    for (const auto& [name, value] : values) {
      std::string unit, doc;
      for (const EffectParameterInfo& p : info->parameters) {
        if (name == p.name) unit = p.unit, doc = p.doc;
      }
      const std::string path = "effects." + effect + "." + name;
      entries.push_back({path, unit, doc, value, error(path), ""});
    }
  }
  // The tube lag measured at each tube length, as two lists of one length
  // (a controller on another tube reads its delta off them).
  if (const auto& by_length = params.pipeline.delta_by_length; !by_length.empty()) {
    Entry lengths{"pipeline.delta_by_length.tube_length", "m",
                  "the tube lengths identify measured delta at"};
    Entry deltas{"pipeline.delta_by_length.delta", "1/s",
                 "the tube's delta measured at each of those lengths"};
    for (const DeltaAtLength& at : by_length) {
      lengths.values.push_back(at.tube_length_m);
      deltas.values.push_back(at.delta_per_s);
    }
    const auto after = std::find_if(entries.begin(), entries.end(),
                                    [](const Entry& e) { return e.path == "pipeline.delta"; });
    entries.insert(after == entries.end() ? after : after + 1, {lengths, deltas});
  }
  InsertChoices(params, &entries);
  return entries;
}

// The shortest text that reads back as the same double (FormatDouble: no
// locale involved), kept a floating-point literal for the typed readers (ROS 2
// declares double parameters; C and MATLAB read doubles either way).
std::string Number(double value) {
  std::string s = FormatDouble(value);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s;
}

// An entry's numbers: its value, or its list between `open` and `close`
// separated by `separator`.
std::string Numbers(const Entry& e, const char* open, const char* separator, const char* close) {
  if (!e.IsList()) return Number(e.value);
  std::string out = open;
  for (std::size_t i = 0; i < e.values.size(); ++i)
    out += (i > 0 ? separator : "") + Number(e.values[i]);
  return out + close;
}

std::string OneLine(const std::string& text) {
  std::string out;
  for (char c : text) out += (c == '\n' || c == '\r') ? ' ' : c;
  return out;
}

std::string Comment(const Entry& e) {
  if (!e.choice.empty()) return e.doc;
  std::string comment = "[" + e.unit + "] " + e.doc;
  if (e.standard_error > 0) comment += "; standard error " + Number(e.standard_error);
  return comment;
}

std::string Identifier(const std::string& path) {
  std::string id = "PNEUMAID_";
  for (char c : path) id += std::isalnum(static_cast<unsigned char>(c)) ? std::toupper(c) : '_';
  return id;
}

std::string Ros2(const Parameters& params, const ExportOptions& options,
                 const std::vector<Entry>& entries) {
  std::ostringstream out;
  out << "# pneumaid parameter set of unit " << params.unit << ", for ROS 2 (--params-file)\n"
      << "# provenance: " << OneLine(params.provenance_yaml) << "\n"
      << "# SI units, pressures absolute; standard errors in the comments.\n"
      << options.ros2_node << ":\n  ros__parameters:\n    unit: " << JsonString(params.unit)
      << "\n";
  // Nested maps: ROS 2 names them with dots (gas.k), as params-v1 does.
  std::vector<std::string> open;
  for (const Entry& e : entries) {
    std::vector<std::string> parts;
    std::stringstream split(e.path);
    std::string part;
    while (std::getline(split, part, '.')) parts.push_back(part);
    std::size_t common = 0;
    while (common < open.size() && common + 1 < parts.size() && open[common] == parts[common])
      ++common;
    open.resize(common);
    for (std::size_t k = common; k + 1 < parts.size(); ++k) {
      out << std::string(4 + 2 * k, ' ') << parts[k] << ":\n";
      open.push_back(parts[k]);
    }
    out << std::string(4 + 2 * (parts.size() - 1), ' ') << parts.back() << ": "
        << (e.choice.empty() ? Numbers(e, "[", ", ", "]") : JsonString(e.choice)) << "  # "
        << Comment(e) << "\n";
  }
  return out.str();
}

// A C string literal (JsonString's \u003c is not a valid escape in C).
std::string CString(const std::string& text) {
  std::string out = "\"";
  for (unsigned char c : text) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += static_cast<char>(c);
    } else if (c < 0x20) {
      char octal[8];
      std::snprintf(octal, sizeof(octal), "\\%03o", c);
      out += octal;
    } else {
      out += static_cast<char>(c);
    }
  }
  return out + "\"";
}

// Text that cannot end a C comment early.
std::string InCComment(std::string text) {
  for (std::size_t at = text.find("*/"); at != std::string::npos; at = text.find("*/"))
    text.replace(at, 2, "* /");
  return text;
}

std::string CHeader(const Parameters& params, const std::vector<Entry>& entries) {
  std::string guard = Identifier("PARAMS_" + params.unit) + "_H";
  std::ostringstream out;
  out << "/* pneumaid parameter set of unit " << InCComment(params.unit) << ".\n"
      << " * Provenance: " << InCComment(OneLine(params.provenance_yaml)) << "\n"
      << " * SI units, pressures absolute. Generated by pneumaid export; do not edit. */\n"
      << "#ifndef " << guard << "\n#define " << guard << "\n\n#define PNEUMAID_UNIT_ID "
      << CString(params.unit) << "\n\n";
  for (const Entry& e : entries) {
    // A list: an initializer for an array, and its length.
    if (e.IsList()) {
      out << "#define " << Identifier(e.path) << "_COUNT " << e.values.size() << "\n";
    }
    const std::string value = !e.choice.empty() ? CString(e.choice)
                              : e.IsList()      ? Numbers(e, "{", ", ", "}")
                                                : "(" + Number(e.value) + ")";
    out << "#define " << Identifier(e.path) << " " << value << " /* " << InCComment(Comment(e))
        << " */\n";
  }
  out << "\n#endif /* " << guard << " */\n";
  return out.str();
}

std::string MatlabString(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("''") : std::string(1, c);
  return out + "'";
}

std::string Matlab(const Parameters& params, const std::vector<Entry>& entries) {
  std::ostringstream out;
  out << "% pneumaid parameter set of unit " << params.unit << ": run this script to get the\n"
      << "% struct pneumaid_params (for Simulink models). SI units, pressures absolute.\n"
      << "% Provenance: " << OneLine(params.provenance_yaml) << "\n"
      << "pneumaid_params = struct();\npneumaid_params.unit = " << MatlabString(params.unit)
      << ";\npneumaid_params.provenance = " << MatlabString(OneLine(params.provenance_yaml))
      << ";\n";
  // The model's choices in a struct of their own: pneumaid_params stays
  // numbers, as a Simulink parameter struct must be.
  out << "pneumaid_model = struct();\n";
  for (const Entry& e : entries) {
    out << (e.choice.empty() ? "pneumaid_params." : "pneumaid_model.") << e.path << " = "
        << (e.choice.empty() ? Numbers(e, "[", " ", "]") : MatlabString(e.choice)) << ";  % "
        << OneLine(Comment(e)) << "\n";
  }
  return out.str();
}

std::string Json(const Parameters& params, const std::vector<Entry>& entries) {
  std::ostringstream out;
  out << "{\"format\": \"pneumaid-export/1\", \"unit\": " << JsonString(params.unit)
      << ", \"provenance\": " << ProvenanceJson(params.provenance_yaml) << ",\n \"parameters\": {";
  // "parameters" holds numbers only; the model's choices are "model"'s.
  std::string model;
  bool first = true;
  for (const Entry& e : entries) {
    if (!e.choice.empty()) {
      model += (model.empty() ? "" : ", ") + JsonString(e.path) + ": " + JsonString(e.choice);
      continue;
    }
    out << (first ? "\n  " : ",\n  ") << JsonString(e.path)
        << ": {\"value\": " << Numbers(e, "[", ", ", "]") << ", \"unit\": " << JsonString(e.unit)
        << ", \"standard_error\": " << (e.standard_error > 0 ? Number(e.standard_error) : "null")
        << "}";
    first = false;
  }
  out << "},\n \"model\": {" << model << "}}\n";
  return out.str();
}

// A ROS 2 params file's node key: a node name, a namespaced one (/ns/node)
// or a wildcard (/**, /ns/*): tokens of letters, digits and '_' not
// starting with a digit, or * or ** after a leading '/', separated by '/'
// with an optional leading one. No empty token: "/", "a//b" and "a/" name no node (and any
// other character made a YAML key that did not parse).
bool IsRos2NodeKey(const std::string& node) {
  // A wildcard only after a leading '/': a key that starts with '*' is a
  // YAML alias, not text.
  const bool absolute = node.size() > 1 && node[0] == '/';
  std::stringstream tokens(absolute ? node.substr(1) : node);
  std::string token;
  int count = 0;
  while (std::getline(tokens, token, '/')) {
    ++count;
    if (token == "*" || token == "**") {
      if (!absolute) return false;
      continue;
    }
    if (token.empty() || std::isdigit(static_cast<unsigned char>(token[0]))) return false;
    if (!std::all_of(token.begin(), token.end(), [](char c) {
          return std::isalnum(static_cast<unsigned char>(c)) || c == '_';
        }))
      return false;
  }
  return count > 0 && node.back() != '/';
}

}  // namespace

bool ParseExportFormat(const std::string& name, ExportFormat* format) {
  if (name == "ros2") return *format = ExportFormat::kRos2, true;
  if (name == "c-header") return *format = ExportFormat::kCHeader, true;
  if (name == "matlab") return *format = ExportFormat::kMatlab, true;
  if (name == "json") return *format = ExportFormat::kJson, true;
  return false;
}

std::string ExportParameters(const Parameters& params, const ExportOptions& options) {
  if (options.format == ExportFormat::kRos2 && !IsRos2NodeKey(options.ros2_node)) {
    throw InputError("export options", 0, 0,
                     "ros2_node: expected a ROS 2 node name, namespaced or a wildcard (tokens of "
                     "letters, digits and '_' not starting with a digit, or * or **, separated "
                     "by '/'), got '" +
                         options.ros2_node + "'");
  }
  const std::vector<Entry> entries = Entries(params);
  switch (options.format) {
    case ExportFormat::kRos2:
      return Ros2(params, options, entries);
    case ExportFormat::kCHeader:
      return CHeader(params, entries);
    case ExportFormat::kMatlab:
      return Matlab(params, entries);
    case ExportFormat::kJson:
      return Json(params, entries);
  }
  return {};
}

}  // namespace pneumaid
