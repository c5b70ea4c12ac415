#include "pneumaid/io/params_yaml.h"

#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "pneumaid/io/files.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/model/effects.h"
#include "pneumaid/model/parameter_table.h"
#include "provenance_map.h"
#include "yaml_reader.h"

namespace pneumaid {
namespace {

const std::set<std::string> kTopLevelKeys = {"format",   "unit",        "gas",       "supply",
                                             "cylinder", "valve",       "pipeline",  "friction",
                                             "effects",  "uncertainty", "provenance"};
const std::set<std::string> kRequiredTopLevelKeys = {"format",   "unit",  "gas",      "supply",
                                                     "cylinder", "valve", "pipeline", "friction"};
// Mapping-valued keys below a section (everything else is a scalar or special).
const std::set<std::string> kSubsections = {"valve.increasing", "valve.decreasing",
                                            "friction.positive", "friction.negative"};

// The model's choices of a set, one entry per key: what it accepts (in the
// order messages list them) and where the choice goes. The format requires
// each but pipeline.model (its default, conductance_lag).
struct ChoiceKey {
  const char* path;
  bool required;
  std::vector<std::string> names;
  // Stores the choice by its index in `names`; null for a key of one name
  // that the model does not store (valve.model, friction.model).
  std::function<void(Parameters*, std::size_t)> set;

  std::string Accepted() const {
    std::string text;
    for (const auto& name : names) text += (text.empty() ? "" : " | ") + name;
    return text;
  }
};

// A key whose names are the enum's own (ToString), stored in `field`.
template <typename Enum>
ChoiceKey EnumChoice(const char* path, bool required, std::vector<Enum> values,
                     Enum& (*field)(Parameters&)) {
  ChoiceKey key{path, required, {}, nullptr};
  for (const Enum value : values) key.names.emplace_back(ToString(value));
  key.set = [values, field](Parameters* params, std::size_t index) {
    field(*params) = values[index];
  };
  return key;
}

const std::vector<ChoiceKey>& ChoiceKeys() {
  static const std::vector<ChoiceKey> keys = {
      EnumChoice<Orientation>("cylinder.orientation", true,
                              {Orientation::kVertical, Orientation::kHorizontal},
                              [](Parameters& p) -> Orientation& { return p.cylinder.orientation; }),
      ChoiceKey{"valve.model", true, {"kvp_poly4"}, nullptr},
      EnumChoice<ValveBranchMode>("valve.branch", true,
                                  {ValveBranchMode::kIncreasing, ValveBranchMode::kDecreasing,
                                   ValveBranchMode::kHysteresis},
                                  [](Parameters& p) -> ValveBranchMode& { return p.valve.branch; }),
      EnumChoice<PipelineModel>(
          "pipeline.model", false,
          {PipelineModel::kConductanceLag, PipelineModel::kFlowLag, PipelineModel::kNone},
          [](Parameters& p) -> PipelineModel& { return p.pipeline.model; }),
      ChoiceKey{"friction.model", true, {"stribeck"}, nullptr}};
  return keys;
}

// The keys a set may have directly under `section` ("friction.positive"),
// for the message that refuses another: read off the tables that the reader
// itself walks.
std::vector<std::string> KeysUnder(const std::string& section) {
  std::set<std::string> keys;
  const std::string prefix = section + ".";
  const auto add = [&](const std::string& path) {
    if (path.compare(0, prefix.size(), prefix) != 0) return;
    keys.insert(path.substr(prefix.size(), path.find('.', prefix.size()) - prefix.size()));
  };
  for (const ScalarParameterInfo& info : ScalarParameterTable()) add(info.path);
  for (const ChoiceKey& key : ChoiceKeys()) add(key.path);
  for (const std::string& path : kSubsections) add(path);
  add("pipeline.delta_by_length");
  return {keys.begin(), keys.end()};
}

const ChoiceKey* FindChoiceKey(const std::string& path) {
  for (const ChoiceKey& key : ChoiceKeys()) {
    if (path == key.path) return &key;
  }
  return nullptr;
}

// Reads one document, remembering where each path was written for messages.
class ParamsReader : internal::YamlReader {
 public:
  explicit ParamsReader(std::string source) : YamlReader(std::move(source)) {}

  Parameters Read(const std::string& text) {
    return Guarded([&] { return ReadDocument(text); });
  }

 private:
  Parameters ReadDocument(const std::string& text) {
    const YAML::Node root =
        LoadMapping(text, "expected a params-v1 mapping (format: pneumaid-params/1, ...)");
    Parameters params;
    ReadTopLevel(root, &params);
    CheckAllRequiredPresent(root);
    CheckValid(params, root);
    return params;
  }

  std::string ScalarText(const YAML::Node& node, const std::string& path) const {
    return Scalar(node, path);
  }

  double Number(const YAML::Node& node, const std::string& path) const {
    const std::string text = ScalarText(node, path);
    const char* end = text.c_str() + text.size();
    double value = 0;
    if (internal::ParseNumber(text.c_str(), end, &value) != end || !std::isfinite(value)) {
      Fail(node, path + ": expected a finite number in SI units, got '" + text + "'");
    }
    return value;
  }

  void ReadChoice(const YAML::Node& node, const ChoiceKey& key, Parameters* params) const {
    const std::string text = ScalarText(node, key.path);
    for (std::size_t i = 0; i < key.names.size(); ++i) {
      if (text != key.names[i]) continue;
      if (key.set) key.set(params, i);
      return;
    }
    Fail(node, std::string(key.path) + ": expected " + key.Accepted() + ", got '" + text + "'");
  }

  void ReadTopLevel(const YAML::Node& root, Parameters* params) {
    for (const auto& entry : root) {
      const std::string key = Key(entry.first);
      const YAML::Node& value = entry.second;
      where_[key] = value;
      if (!kTopLevelKeys.count(key)) {
        Fail(entry.first, "unknown key '" + key + "' (expected " +
                              internal::JoinNames({kTopLevelKeys.begin(), kTopLevelKeys.end()}) +
                              ")");
      }
      NotEmpty(entry.first, value, key);
      if (key == "format") {
        if (ScalarText(value, key) != kParamsFormat) {
          Fail(value, std::string("expected format: ") + kParamsFormat);
        }
      } else if (key == "unit") {
        params->unit = ScalarText(value, key);
        // The rig format's unit id (the set names the unit its logs name).
        if (!IsUnitId(params->unit))
          Fail(value, "unit: expected an id of letters, digits, '.', '_' or '-'");
      } else if (key == "effects") {
        ReadEffects(value, params);
      } else if (key == "uncertainty") {
        ReadUncertainty(value, params);
      } else if (key == "provenance") {
        if (!value.IsMap()) Fail(value, "provenance: expected a mapping");
        // Its texts stay quoted where another reader would misread them (a
        // unit 0001 in an export's comment or a report).
        params->provenance_yaml = EmitProvenance(value);
      } else {
        ReadSection(value, key, params);
      }
    }
    for (const auto& key : kRequiredTopLevelKeys) {
      if (!root[key]) Fail(root, "missing required key '" + key + "'");
    }
  }

  void ReadSection(const YAML::Node& node, const std::string& prefix, Parameters* params) {
    if (!node.IsMap()) Fail(node, prefix + ": expected a mapping");
    for (const auto& entry : node) {
      const std::string path = prefix + "." + Key(entry.first);
      const YAML::Node& value = entry.second;
      where_[path] = value;
      NotEmpty(entry.first, value, path);
      if (const ScalarParameterInfo* info = FindScalarParameter(path)) {
        info->ref(*params) = Number(value, path);
      } else if (kSubsections.count(path)) {
        ReadSection(value, path, params);
      } else if (!ReadSpecial(value, path, params)) {
        Fail(entry.first, "unknown key '" + path + "' (expected " +
                              internal::JoinNames(KeysUnder(prefix)) + ")");
      }
    }
  }

  // Non-numeric keys of the sections. False when `path` is not one.
  bool ReadSpecial(const YAML::Node& value, const std::string& path, Parameters* params) {
    if (const ChoiceKey* key = FindChoiceKey(path)) {
      ReadChoice(value, *key, params);
    } else if (path == "pipeline.delta_by_length") {
      ReadDeltaByLength(value, params);
    } else {
      return false;
    }
    return true;
  }

  void ReadDeltaByLength(const YAML::Node& node, Parameters* params) {
    if (!node.IsSequence()) Fail(node, "pipeline.delta_by_length: expected a list");
    for (const auto& item : node) {
      if (!item.IsMap()) Fail(item, "pipeline.delta_by_length: expected {tube_length, delta}");
      // Validate names an entry "pipeline.delta_by_length[i]": its line.
      where_["pipeline.delta_by_length[" + std::to_string(params->pipeline.delta_by_length.size()) +
             "]"] = static_cast<const YAML::Node&>(item);
      DeltaAtLength entry;
      for (const auto& field : item) {
        const std::string key = Key(field.first);
        const std::string path = "pipeline.delta_by_length." + key;
        if (key == "tube_length") {
          entry.tube_length_m = Number(field.second, path);
        } else if (key == "delta") {
          entry.delta_per_s = Number(field.second, path);
        } else {
          Fail(field.first, "unknown key '" + path + "' (expected tube_length, delta)");
        }
      }
      if (!item["tube_length"] || !item["delta"]) {
        Fail(item, "pipeline.delta_by_length: each entry needs tube_length and delta");
      }
      params->pipeline.delta_by_length.push_back(entry);
    }
  }

  void ReadEffects(const YAML::Node& node, Parameters* params) {
    if (!node.IsMap()) Fail(node, "effects: expected a mapping name -> {parameter: value}");
    for (const auto& entry : node) {
      const std::string name = Key(entry.first);
      const EffectInfo* effect = FindEffect(name);
      if (effect == nullptr) {
        std::string known;
        for (const auto& e : EffectCatalog())
          known += (known.empty() ? "" : ", ") + std::string(e.name);
        Fail(entry.first, "unknown effect '" + name + "' (catalog: " + known + ")");
      }
      where_["effects." + name] = entry.second;
      if (!entry.second.IsMap()) Fail(entry.second, "effects." + name + ": expected a mapping");
      auto& values = params->effects[name];
      for (const auto& field : entry.second) {
        const std::string path = "effects." + name + "." + Key(field.first);
        where_[path] = field.second;
        values[Key(field.first)] = Number(field.second, path);
      }
    }
  }

  void ReadUncertainty(const YAML::Node& node, Parameters* params) {
    if (!node.IsMap()) Fail(node, "uncertainty: expected a mapping path -> standard error");
    for (const auto& entry : node) {
      const std::string path = Key(entry.first);
      const double value = Number(entry.second, "uncertainty." + path);
      if (!(value >= 0)) Fail(entry.second, "uncertainty." + path + ": expected >= 0");
      where_["uncertainty." + path] = entry.first;
      params->uncertainty[path] = value;
    }
  }

  // Every number of the table and the model's choices (the format requires
  // them; only pipeline.model has a default, conductance_lag), each missing
  // one named at the nearest mapping written.
  void CheckAllRequiredPresent(const YAML::Node& root) const {
    const auto missing = [&](const std::string& path, const std::string& what) {
      if (where_.count(path)) return;
      Fail(WhereWritten(path.substr(0, path.rfind('.')), root),
           "missing required key '" + path + "'" + what);
    };
    for (const auto& info : ScalarParameterTable()) {
      missing(info.path, std::string(" [") + info.unit + "]: " + info.doc);
    }
    for (const ChoiceKey& key : ChoiceKeys()) {
      if (key.required) missing(key.path, " (" + key.Accepted() + ")");
    }
  }

  // The node written for `path`, or for its nearest written ancestor.
  YAML::Node WhereWritten(std::string path, const YAML::Node& root) const {
    while (!path.empty()) {
      const auto found = where_.find(path);
      if (found != where_.end()) return found->second;
      const auto dot = path.rfind('.');
      path = dot == std::string::npos ? "" : path.substr(0, dot);
    }
    return root;
  }

  void CheckValid(const Parameters& params, const YAML::Node& root) const {
    for (const auto& problem : Validate(params)) {
      Fail(WhereWritten(problem.path, root), problem.path + ": " + problem.message);
    }
    for (const auto& [path, value] : params.uncertainty) {
      double ignored = 0;
      if (!GetParameter(params, path, &ignored)) {
        Fail(where_.at("uncertainty." + path), "uncertainty: '" + path + "' names no parameter");
      }
    }
  }

  std::map<std::string, YAML::Node> where_;
};

YAML::Node Scalar(double value) { return YAML::Node(FormatDouble(value)); }

YAML::Node FlowMap() {
  YAML::Node node(YAML::NodeType::Map);
  node.SetStyle(YAML::EmitterStyle::Flow);
  return node;
}

// The section of `path` prefix as a YAML mapping, from the parameter table.
void FillFromTable(const Parameters& params, const std::string& prefix, YAML::Node* node) {
  for (const auto& info : ScalarParameterTable()) {
    const std::string path = info.path;
    if (path.compare(0, prefix.size() + 1, prefix + ".") != 0) continue;
    const std::string key = path.substr(prefix.size() + 1);
    if (key.find('.') != std::string::npos) continue;  // belongs to a subsection
    (*node)[key] = Scalar(info.get(params));
  }
}

YAML::Node Section(const Parameters& params, const std::string& prefix, bool flow) {
  YAML::Node node = flow ? FlowMap() : YAML::Node(YAML::NodeType::Map);
  FillFromTable(params, prefix, &node);
  return node;
}

}  // namespace

std::string FormatDouble(double value) {
  char buffer[32];
  // Shortest round trip, %g-like choice between fixed and scientific.
  const auto result =
      std::to_chars(buffer, buffer + sizeof(buffer), value, std::chars_format::general);
  return std::string(buffer, result.ptr);
}

Parameters ParamsFromYaml(const std::string& text, const std::string& source_name) {
  return ParamsReader(source_name).Read(text);
}

Parameters LoadParams(const std::string& path) {
  return ParamsFromYaml(ReadTextFile(path, "parameter file"), path);
}

std::string ParamsToYaml(const Parameters& params) {
  YAML::Node root(YAML::NodeType::Map);
  root["format"] = kParamsFormat;
  root["unit"] = params.unit;
  root["gas"] = FlowMap();
  root["gas"]["k"] = Scalar(params.gas.heat_capacity_ratio);
  root["gas"]["R"] = Scalar(params.gas.gas_constant_J_per_kgK);
  root["gas"]["T"] = Scalar(params.gas.temperature_K);
  root["supply"] = Section(params, "supply", true);
  root["cylinder"] = Section(params, "cylinder", false);
  root["cylinder"]["orientation"] = ToString(params.cylinder.orientation);
  root["valve"] = YAML::Node(YAML::NodeType::Map);
  root["valve"]["model"] = FindChoiceKey("valve.model")->names.front();
  root["valve"]["normalization"] = Scalar(params.valve.normalization);
  root["valve"]["increasing"] = Section(params, "valve.increasing", true);
  root["valve"]["decreasing"] = Section(params, "valve.decreasing", true);
  root["valve"]["branch"] = ToString(params.valve.branch);
  root["pipeline"] = YAML::Node(YAML::NodeType::Map);
  root["pipeline"]["model"] = ToString(params.pipeline.model);
  YAML::Node pipeline = root["pipeline"];  // a handle into root
  FillFromTable(params, "pipeline", &pipeline);
  YAML::Node by_length(YAML::NodeType::Sequence);
  by_length.SetStyle(YAML::EmitterStyle::Flow);
  for (const auto& entry : params.pipeline.delta_by_length) {
    YAML::Node item = FlowMap();
    item["tube_length"] = Scalar(entry.tube_length_m);
    item["delta"] = Scalar(entry.delta_per_s);
    by_length.push_back(item);
  }
  root["pipeline"]["delta_by_length"] = by_length;
  root["friction"] = YAML::Node(YAML::NodeType::Map);
  root["friction"]["model"] = FindChoiceKey("friction.model")->names.front();
  root["friction"]["positive"] = Section(params, "friction.positive", true);
  root["friction"]["negative"] = Section(params, "friction.negative", true);
  YAML::Node effects = FlowMap();
  for (const auto& [name, values] : params.effects) {
    YAML::Node effect = FlowMap();
    for (const auto& [key, value] : values) effect[key] = Scalar(value);
    effects[name] = effect;
  }
  root["effects"] = effects;
  YAML::Node uncertainty = params.uncertainty.empty() ? FlowMap() : YAML::Node(YAML::NodeType::Map);
  for (const auto& [path, value] : params.uncertainty) uncertainty[path] = Scalar(value);
  root["uncertainty"] = uncertainty;
  // A set built in code may carry any text: what is not a mapping (or not
  // YAML at all) is kept under `given`, as every writer of an entry does.
  YAML::Node provenance = ProvenanceMap(params.provenance_yaml);
  root["provenance"] = provenance.size() == 0 ? FlowMap() : provenance;
  YAML::Emitter emitter;
  emitter << YAML::BeginMap;
  for (const auto& entry : root) {
    const std::string key = entry.first.as<std::string>();
    emitter << YAML::Key << key << YAML::Value;
    // A unit id another YAML reader would take for a number, a bool or null
    // ("0001", "1e3", "true", ".nan") is written quoted; yaml-cpp quotes only
    // what it reads otherwise itself.
    if (key == "unit" && ReadAsOtherThanText(params.unit)) {
      emitter << YAML::DoubleQuoted << params.unit;
    } else if (key == "provenance") {
      EmitProvenanceNode(entry.second, false, &emitter);
    } else {
      emitter << entry.second;
    }
  }
  emitter << YAML::EndMap;
  // yaml-cpp reports an emitter error in its state, not by throwing.
  if (!emitter.good()) throw std::logic_error("parameter set: " + emitter.GetLastError());
  return std::string(emitter.c_str()) + "\n";
}

void SaveParams(const Parameters& params, const std::string& path) {
  const auto problems = Validate(params);
  if (!problems.empty()) {
    throw InputError(path, 0, 0,
                     "refusing to write an invalid parameter set: " + problems.front().path + ": " +
                         problems.front().message);
  }
  WriteFileAtomically(path, ParamsToYaml(params));
}

}  // namespace pneumaid
