// The effect catalog: named, optional extensions of the base model.
//
// One catalog is shared by the parameter loader, the simulator, the synthetic
// rig and the discrepancy workflow. An effect is present in a parameter set
// when its name is a key of `effects`; its parameters are then all required.
#pragma once

#include <string>
#include <vector>

#include "pneumaid/model/parameter_table.h"

namespace pneumaid {

struct EffectParameterInfo {
  const char* name;  // "tau"
  const char* unit;  // "s"
  const char* doc;
  ValueRange range;  // what the model accepts (validation)
  // What a real rig plausibly has: the bounds a fit of the effect (diagnose)
  // searches, and a typical size it starts from. docs/effects.md gives why.
  double plausible_min, plausible_max, typical;
};

struct EffectInfo {
  const char* name;  // "valve_lag"
  const char* doc;
  std::vector<EffectParameterInfo> parameters;
  // False for effects the catalog names but the simulator cannot honour yet;
  // simulating a parameter set that holds one is refused, never ignored.
  bool simulated;
  // True for effects that change the friction the rod feels from the paper's
  // Stribeck law with exact stick (rod_replay.h): the friction fit and the
  // friction_replay stage model that law alone, so friction they fit is not
  // the friction of a set with such an effect.
  bool acts_on_friction = false;
};

const std::vector<EffectInfo>& EffectCatalog();

// nullptr when `name` is not in the catalog.
const EffectInfo* FindEffect(const std::string& name);

// "effects.<name>.<parameter>" -> (name, parameter); false for other paths.
bool SplitEffectPath(const std::string& path, std::string* name, std::string* parameter);

// The catalog's entry of an effect parameter's path ("effects.valve_lag.tau");
// nullptr when the path names no effect parameter of the catalog.
const EffectParameterInfo* FindEffectParameter(const std::string& path);

}  // namespace pneumaid
