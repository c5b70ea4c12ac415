#include "pneumaid/model/actuator.h"

namespace pneumaid {

bool ModelRegularization::IsValid(std::string* error) const {
  const auto fail = [error](const char* what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (!(stick_velocity_m_per_s > 0)) return fail("stick_velocity_m_per_s must be > 0");
  if (!(end_stop_stiffness_N_per_m > 0)) return fail("end_stop_stiffness_N_per_m must be > 0");
  if (!(end_stop_damping_ratio >= 0)) return fail("end_stop_damping_ratio must be >= 0");
  if (!(end_stop_engagement_depth_m > 0)) return fail("end_stop_engagement_depth_m must be > 0");
  if (!(linear_flow_ratio > 0.9 && linear_flow_ratio < 1)) {
    return fail("linear_flow_ratio must be in (0.9, 1)");
  }
  if (!(flow_lag_pressure_floor_Pa > 0)) return fail("flow_lag_pressure_floor_Pa must be > 0");
  if (!(minimum_volume_fraction > 0 && minimum_volume_fraction < 1)) {
    return fail("minimum_volume_fraction must be in (0, 1)");
  }
  return true;
}

ActuatorLayout ActuatorLayout::For(const Parameters& params) {
  ActuatorLayout layout;
  const auto has = [&params](const char* effect) { return params.effects.count(effect) > 0; };
  layout.valve_lag = has("valve_lag");
  layout.conductance_lag = params.pipeline.model == PipelineModel::kConductanceLag ||
                           (params.pipeline.model == PipelineModel::kNone && has("pipeline_lag"));
  layout.flow_lag = params.pipeline.model == PipelineModel::kFlowLag;
  layout.flow_sensor_lag = has("flow_sensor_lag");
  layout.heat_transfer = has("heat_transfer");
  layout.supply_droop = has("supply_droop");
  int next = 4;
  const auto take = [&next](bool present, int count) {
    if (!present) return -1;
    const int begin = next;
    next += count;
    return begin;
  };
  layout.opening_begin = take(layout.valve_lag, kValvePairCount);
  layout.conductance_begin = take(layout.conductance_lag, kValvePairCount);
  layout.flow_begin = take(layout.flow_lag, 2);
  layout.sensor_begin = take(layout.flow_sensor_lag, 2);
  layout.temperature_begin = take(layout.heat_transfer, 2);
  layout.size = next;
  return layout;
}

}  // namespace pneumaid
