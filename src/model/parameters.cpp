#include "pneumaid/model/parameters.h"

#include <cstdio>

#include "pneumaid/model/effects.h"
#include "pneumaid/model/parameter_table.h"

namespace pneumaid {
namespace {

void CheckScalarRanges(const Parameters& params, std::vector<ParameterProblem>* problems) {
  for (const auto& info : ScalarParameterTable()) {
    const double value = info.get(params);
    if (!info.range.Contains(value)) {
      char got[32];
      std::snprintf(got, sizeof(got), "%.9g", value);  // -1e-09, not -0.000000
      problems->push_back(
          {info.path, "expected " + info.range.Describe() + " " + info.unit + ", got " + got});
    }
  }
}

void CheckCrossFieldRules(const Parameters& params, std::vector<ParameterProblem>* problems) {
  if (params.cylinder.area_2_m2 >= params.cylinder.area_1_m2) {
    problems->push_back({"cylinder.area_2",
                         "expected the rod-side area to be smaller than area_1 (the rod "
                         "takes up part of the piston)"});
  }
  if (params.supply.supply_pressure_Pa <= params.supply.atmospheric_pressure_Pa) {
    problems->push_back({"supply.supply_pressure",
                         "expected the supply pressure to exceed the atmospheric pressure "
                         "(both absolute)"});
  }
  for (size_t i = 0; i < params.pipeline.delta_by_length.size(); ++i) {
    const auto& entry = params.pipeline.delta_by_length[i];
    const std::string path = "pipeline.delta_by_length[" + std::to_string(i) + "]";
    if (!(entry.tube_length_m >= 0)) {
      problems->push_back({path, "expected tube_length >= 0 m"});
    }
    if (!(entry.delta_per_s > 0)) problems->push_back({path, "expected delta > 0 1/s"});
  }
  if (params.effects.count("pipeline_lag") && params.pipeline.model != PipelineModel::kNone) {
    problems->push_back({"effects.pipeline_lag",
                         "pipeline_lag adds the Eq. 5 lag to a base model without one; "
                         "expected pipeline.model: none"});
  }
}

void CheckEffects(const Parameters& params, std::vector<ParameterProblem>* problems) {
  for (const auto& [name, values] : params.effects) {
    const EffectInfo* effect = FindEffect(name);
    if (effect == nullptr) {
      problems->push_back({"effects." + name, "unknown effect name"});
      continue;
    }
    for (const auto& [key, value] : values) {
      const std::string path = "effects." + name + "." + key;
      const EffectParameterInfo* info = nullptr;
      for (const auto& candidate : effect->parameters) {
        if (key == candidate.name) info = &candidate;
      }
      if (info == nullptr) {
        problems->push_back({path, "unknown parameter of effect " + name});
      } else if (!info->range.Contains(value)) {
        problems->push_back({path, "expected " + info->range.Describe() + " " + info->unit});
      }
    }
    for (const auto& info : effect->parameters) {
      if (!values.count(info.name)) {
        problems->push_back({"effects." + name + "." + info.name, "missing parameter"});
      }
    }
  }
}

}  // namespace

std::vector<ParameterProblem> Validate(const Parameters& params) {
  std::vector<ParameterProblem> problems;
  CheckScalarRanges(params, &problems);
  CheckCrossFieldRules(params, &problems);
  CheckEffects(params, &problems);
  return problems;
}

const char* ToString(Orientation value) {
  return value == Orientation::kVertical ? "vertical" : "horizontal";
}

const char* ToString(ValveBranchMode value) {
  switch (value) {
    case ValveBranchMode::kIncreasing:
      return "increasing";
    case ValveBranchMode::kDecreasing:
      return "decreasing";
    case ValveBranchMode::kHysteresis:
      return "hysteresis";
  }
  return "?";
}

const char* ToString(PipelineModel value) {
  switch (value) {
    case PipelineModel::kConductanceLag:
      return "conductance_lag";
    case PipelineModel::kFlowLag:
      return "flow_lag";
    case PipelineModel::kNone:
      return "none";
  }
  return "?";
}

}  // namespace pneumaid
