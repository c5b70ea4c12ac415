// The model's derivatives with respect to the free parameters (and the
// initial pressures) for SimulateWithSensitivities (internal to src/sim/).
#pragma once

#include <sundials/sundials_nvector.h>

#include <memory>
#include <vector>

#include "lag_history.h"
#include "model_data.h"
#include "pneumaid/sim/sensitivities.h"

namespace pneumaid::internal {

// What a run with sensitivities evaluates in Jets whose derivative j is taken
// with respect to free parameter j (the coefficients carry dc/dp_j, the state
// carries s_j = dy/dp_j). Implemented for a few lane counts (LanedJets below):
// Jet arithmetic is the part of a sensitivity step that grows with the lanes,
// so a 2-parameter fit should not pay for 16.
class ParameterJets {
 public:
  virtual ~ParameterJets() = default;
  // CVODES' sensitivity right-hand sides, all at once: s_j' = f_y s_j + f_p_j.
  // Returns 1 (recoverable) on a non-finite rate.
  virtual int Rates(const ModelData& data, const double* y, const N_Vector* s,
                    N_Vector* rates) const = 0;
  // The total derivative g_y s_j + g_p_j of switching function `fired`.
  virtual void SwitchingDerivatives(const ModelData& data, const double* y, const N_Vector* s,
                                    int fired, double* dg_dp) const = 0;
  // Row `row` of the output sensitivities.
  virtual void AppendOutputs(const ModelData& data, const double* y, const N_Vector* s,
                             Eigen::Index row, TrajectorySensitivities* out) const = 0;
  // dy(t0)/dp_j: the chamber states and settled lags depend on the
  // parameters even though the initial pressures and position do not.
  virtual std::vector<std::vector<double>> Initial(
      const ModelData& data, const InitialState& initial, const CommandSignal& command,
      const ValveCommandTracker& fresh, const ValveCommand& initial_command, double t0) const = 0;
};

// The fewest lanes of those compiled that hold every sensitivity column.
std::unique_ptr<const ParameterJets> MakeParameterJets(const Parameters& params,
                                                       const SensitivityOptions& sensitivity,
                                                       const ModelRegularization& regularization);

}  // namespace pneumaid::internal
