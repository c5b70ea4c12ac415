// Forward parameter sensitivities of a simulation (CVODES), for output-error
// fitting through the simulator.
//
// The sensitivity equations s' = (df/dy) s + df/dp are evaluated in one pass
// of the model's templates with ceres::Jet (the Jet carries one direction per
// parameter). The parameter -> coefficient map (MakeActuatorCoefficients) is a
// small algebraic map; its derivative is taken by central differences once per
// run (its error is ~1e-10 relative, far below the integration error).
//
// Events (stick/slip switches, end-stop impacts) move with the parameters.
// At each one the sensitivities jump by the classical condition
//   s+ = H (s- + f- tau_p) - f+ tau_p,   tau_p = -(g_y s- + g_p) / (g_y f-),
// with g the switching function that fired, f-/f+ the right-hand sides before
// and after the switch and H the Jacobian of the state reset (v := 0 when the
// rod stops, x := +-L/2 as well at an end stop). They are then exact
// derivatives of the simulated outputs wherever the sequence of events does not
// change with the parameters (docs/refinement.md).
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "pneumaid/sim/simulate.h"

namespace pneumaid {

inline constexpr int kMaxSensitivityParameters = 16;
// Columns for the initial chamber pressures, p1(t0) and p2(t0), when asked for.
inline constexpr int kInitialPressureColumns = 2;

struct SensitivityOptions {
  // Free parameters by params-v1 path ("friction.positive.Fs"), at most
  // kMaxSensitivityParameters.
  std::vector<std::string> parameter_paths;
  // Typical magnitude of each parameter (same order): scales the sensitivity
  // tolerances and the step of the coefficient map's central differences.
  std::vector<double> parameter_scales;
  // Include the sensitivities in CVODE's local error test: more accurate, more
  // steps. Off is the usual choice for fitting (staggered corrector only).
  bool error_control = false;
  // Sensitivity tolerances relative to the state's (CVODES' estimated ones
  // when 1). Larger values let the staggered corrector stop sooner; the
  // Jacobian of a fit needs far fewer digits than the trajectory.
  double tolerance_factor = 1.0;
  // Also the sensitivities to the initial chamber pressures p1(t0), p2(t0)
  // [per Pa]: two more columns after the parameters', in that order. A fit
  // can then estimate where a run started instead of trusting the noisy
  // logged pressures, which stick-slip amplifies (docs/refinement.md).
  bool initial_pressures = false;

  // Columns of the output sensitivities: the parameters, then the initial
  // pressures when asked for; at most kMaxSensitivityParameters.
  int Columns() const {
    return static_cast<int>(parameter_paths.size()) +
           (initial_pressures ? kInitialPressureColumns : 0);
  }

  bool IsValid(const Parameters& params, std::string* error) const;
};

// d(channel)/d(parameter) at every output time: one row per sample, one column
// per SensitivityOptions column, in SI units of the channel per unit of the
// parameter.
struct TrajectorySensitivities {
  Eigen::MatrixXd x, p1, p2, q1, q2;
};

// Simulate (same contract) plus sensitivities of x, p1, p2, q1, q2 with
// respect to the parameters named in `sensitivity`.
SimulationSummary SimulateWithSensitivities(const Parameters& params, const CommandSignal& command,
                                            const InitialState& initial,
                                            const std::vector<double>& output_times_s,
                                            const SimulationOptions& options,
                                            const SensitivityOptions& sensitivity, Trajectory* out,
                                            TrajectorySensitivities* derivatives);

}  // namespace pneumaid
