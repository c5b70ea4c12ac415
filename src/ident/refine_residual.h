// Refinement (refine.h), its residual block: one experiment's weighted
// residuals through the simulator, with the Jacobian from the CVODES forward
// sensitivities (or central differences), as one Ceres cost function.
#pragma once

#include <ceres/ceres.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <vector>

#include "pneumaid/eval/metrics.h"
#include "pneumaid/ident/refine.h"
#include "pneumaid/sim/sensitivities.h"
#include "refine_parameters.h"
#include "refine_runs.h"

namespace pneumaid::refine_internal {

// Sensitivity tolerances 100 x the state's during fitting: the Jacobian needs
// a few digits, and the staggered corrector then stops sooner (22 % fewer
// instructions per sensitivity run on the benchmark's logs).
constexpr double kSensitivityToleranceFactor = 100.0;

// The last evaluation of a residual block, kept so that the covariance and
// the final costs need no extra simulation.
struct EvaluationCache {
  std::vector<double> z;  // the free parameters' coordinates, then the start offsets
  Eigen::VectorXd residuals;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> jacobian;  // d r / d z
};

// All weighted residuals of one experiment, (sim - measured) factor, channel
// after channel, then the priors of an estimated start; the Jacobian from the
// forward sensitivities. Parameter blocks: the free parameters' coordinates
// (shared), and the experiment's StartOffsets when it FitsStart. Returns false
// (Ceres rejects the step) when the simulation fails or the parameter set is
// not physical; never throws. The bounds are built into the coordinates
// (ParameterMap).
class ExperimentResidual final : public ceres::CostFunction {
 public:
  ExperimentResidual(const Parameters* base, const ParameterMap* map,
                     const FitExperiment* experiment, const SimulationOptions* simulation,
                     JacobianMethod method)
      : base_(base), map_(map), experiment_(experiment), simulation_(simulation), method_(method) {
    set_num_residuals(static_cast<int>(experiment->residuals()));
    mutable_parameter_block_sizes()->push_back(map->size());
    if (experiment->FitsStart()) mutable_parameter_block_sizes()->push_back(kStartOffsets);
  }

  // Coordinates z of the Jacobian: the free parameters', then the start's.
  int columns() const { return map_->size() + (experiment_->FitsStart() ? kStartOffsets : 0); }

  bool Evaluate(double const* const* blocks, double* residuals, double** jacobians) const override {
    try {
      const std::vector<double> z = Coordinates(*experiment_, blocks[0], map_->size(),
                                                experiment_->FitsStart() ? blocks[1] : nullptr);
      if (jacobians == nullptr) return EvaluateOrFail(z, residuals, nullptr);
      std::vector<double> jacobian(static_cast<size_t>(num_residuals() * columns()));
      if (!EvaluateOrFail(z, residuals, jacobian.data())) return false;
      Remember(z, residuals, jacobian.data());
      SplitIntoBlocks(jacobian, jacobians);
      return true;
    } catch (...) {
      return false;  // never throw through Ceres
    }
  }

  // The residuals and Jacobian at z, from the cache of the last Jacobian
  // evaluation when it was at z (Ceres evaluates one at every accepted
  // point, so the optimum's usually is).
  bool ResidualsAndJacobian(const std::vector<double>& z, const EvaluationCache** out) const {
    if (cache_.z != z || cache_.jacobian.size() == 0) {
      std::vector<double> r(static_cast<size_t>(num_residuals()));
      std::vector<double> j(r.size() * static_cast<size_t>(columns()));
      try {
        if (!EvaluateOrFail(z, r.data(), j.data())) return false;
      } catch (...) {
        return false;
      }
      Remember(z, r.data(), j.data());
    }
    *out = &cache_;
    return true;
  }

  // The residuals alone at z (the plain run); false where it fails. With
  // `use`, what the run read of the friction (always simulated then).
  bool ResidualsAt(const std::vector<double>& z, Eigen::VectorXd* residuals,
                   FrictionUse* use = nullptr) const {
    residuals->resize(num_residuals());
    try {
      if (use != nullptr) return Residuals(z.data(), residuals->data(), use);
      return EvaluateOrFail(z, residuals->data(), nullptr);
    } catch (...) {
      return false;
    }
  }

  // 0.5 |r|^2 at the first Jacobian evaluation (NaN before one).
  double FirstCost() const { return first_cost_; }

 private:
  void Remember(const std::vector<double>& z, const double* residuals,
                const double* jacobian) const {
    const int n = num_residuals();
    if (std::isnan(first_cost_)) {
      first_cost_ = 0.5 * Eigen::Map<const Eigen::VectorXd>(residuals, n).squaredNorm();
    }
    cache_.z = z;
    cache_.residuals = Eigen::Map<const Eigen::VectorXd>(residuals, n);
    cache_.jacobian =
        Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
            jacobian, n, columns());
  }

  // Ceres' blocks (row-major, each its own columns) from the whole Jacobian.
  void SplitIntoBlocks(const std::vector<double>& jacobian, double** blocks) const {
    const int m = map_->size(), cols = columns();
    for (int i = 0; i < num_residuals(); ++i) {
      const double* row = jacobian.data() + static_cast<size_t>(i) * cols;
      if (blocks[0] != nullptr) std::copy(row, row + m, blocks[0] + static_cast<size_t>(i) * m);
      if (experiment_->FitsStart() && blocks[1] != nullptr) {
        std::copy(row + m, row + cols, blocks[1] + static_cast<size_t>(i) * kStartOffsets);
      }
    }
  }

  bool EvaluateOrFail(const std::vector<double>& z, double* residuals, double* jacobian) const {
    // Ceres evaluates the residuals at a trial point, then, if it accepts
    // the step, residuals and Jacobian at the same point (and the verdict may
    // ask for the residuals again): the plain run is not repeated.
    const bool known = last_residuals_.size() == num_residuals() && z == last_z_;
    if (known) {
      std::copy(last_residuals_.data(), last_residuals_.data() + num_residuals(), residuals);
    } else {
      if (!Residuals(z.data(), residuals)) return false;
      last_z_ = z;
      last_residuals_ = Eigen::Map<const Eigen::VectorXd>(residuals, num_residuals());
    }
    if (jacobian == nullptr) return true;
    return method_ == JacobianMethod::kCentralDifferences ? CentralDifferences(z, jacobian)
                                                          : Sensitivities(z.data(), jacobian);
  }

  // The residuals always come from the plain simulation: the run with
  // sensitivities takes slightly different steps, and with stick-slip its
  // trajectory differs by more than Levenberg-Marquardt's cost comparisons
  // between trial points (residuals only) and accepted points tolerate.
  bool Residuals(const double* z, double* residuals, FrictionUse* use = nullptr) const {
    const Parameters params = WithValues(*base_, *map_, z);
    if (!Validate(params).empty()) return false;
    const FitExperiment& e = *experiment_;
    Trajectory sim;
    SimulationOptions recording;  // what the run reads of the friction, when asked
    if (use != nullptr) {
      recording = *simulation_;
      recording.record_friction_use = true;
    }
    const SimulationSummary summary =
        Simulate(params, e.command, StartOf(e, z + map_->size()), e.measured.t_s,
                 use != nullptr ? recording : *simulation_, &sim);
    if (!summary.ok() || sim.size() != e.measured.size()) return false;
    if (use != nullptr) *use = summary.friction_use;
    const long n = static_cast<long>(e.measured.size());
    long row = 0;
    for (const Channel& c : e.channels) {
      std::vector<double> simulated = sim.*c.values;
      if (c.meter_tau_s > 0) simulated = FirstOrderLag(sim.t_s, simulated, c.meter_tau_s);
      const std::vector<double>& measured = e.measured.*c.values;
      for (long i = 0; i < n; ++i) residuals[row + i] = c.factor * (simulated[i] - measured[i]);
      row += n;
    }
    if (e.FitsStart()) {  // the priors: offsets in units of the logged values' errors
      for (int k = 0; k < kStartOffsets; ++k) residuals[row++] = z[map_->size() + k];
    }
    return std::all_of(residuals, residuals + row, [](double r) { return std::isfinite(r); });
  }

  // The Jacobian from the CVODES forward sensitivities.
  bool Sensitivities(const double* z, double* jacobian) const {
    const Parameters params = WithValues(*base_, *map_, z);
    const FitExperiment& e = *experiment_;
    const int m = map_->size(), cols = columns();
    SensitivityOptions s;
    for (int j = 0; j < m; ++j) {
      s.parameter_paths.push_back(map_->free[j].path);
      // Typical magnitude for the sensitivity tolerances: the value itself
      // (a parameter near 0 takes a small fraction of its range).
      const FreeParameter& free = map_->free[j];
      s.parameter_scales.push_back(
          std::max(std::fabs(map_->ToValue(j, z[j])), 1e-6 * (free.upper - free.lower)));
    }
    s.tolerance_factor = kSensitivityToleranceFactor;
    s.initial_pressures = e.FitsStart();
    Trajectory sim;
    TrajectorySensitivities sens;
    const SimulationSummary summary = SimulateWithSensitivities(
        params, e.command, StartOf(e, z + m), e.measured.t_s, *simulation_, s, &sim, &sens);
    if (!summary.ok() || sim.size() != e.measured.size()) return false;
    std::fill(jacobian, jacobian + num_residuals() * cols, 0.0);
    long row = 0;
    for (const Channel& c : e.channels) {
      FillJacobian(c, sim.t_s, sens, z, row, jacobian);
      row += static_cast<long>(e.measured.size());
    }
    if (e.FitsStart()) {
      for (int k = 0; k < kStartOffsets; ++k) jacobian[(row + k) * cols + m + k] = 1.0;
    }
    return std::all_of(jacobian, jacobian + num_residuals() * cols,
                       [](double d) { return std::isfinite(d); });
  }

  // The baseline Jacobian: (r(z + h e_j) - r(z - h e_j)) / 2h.
  bool CentralDifferences(const std::vector<double>& z, double* jacobian) const {
    const int cols = columns();
    const int n = num_residuals();
    std::vector<double> shifted = z, up(n), down(n);
    constexpr double kStep = 1e-5;  // in theta: a relative change of about 1e-5
    for (int j = 0; j < cols; ++j) {
      shifted[j] = z[j] + kStep;
      if (!Residuals(shifted.data(), up.data())) return false;
      shifted[j] = z[j] - kStep;
      if (!Residuals(shifted.data(), down.data())) return false;
      shifted[j] = z[j];
      for (int i = 0; i < n; ++i) jacobian[i * cols + j] = (up[i] - down[i]) / (2 * kStep);
    }
    return true;
  }

  // Rows [row, row + n) of the row-major Jacobian d residual / d z: the free
  // parameters' columns, and the start's when it is estimated.
  void FillJacobian(const Channel& c, const std::vector<double>& t_s,
                    const TrajectorySensitivities& sens, const double* z, long row,
                    double* jacobian) const {
    const int m = map_->size(), cols = columns();
    const Eigen::MatrixXd& d = sens.*c.derivatives;
    for (int j = 0; j < cols; ++j) {
      std::vector<double> column(d.col(j).data(), d.col(j).data() + d.rows());
      // The meter lag is linear: the lagged sensitivity is the sensitivity lagged.
      if (c.meter_tau_s > 0) column = FirstOrderLag(t_s, column, c.meter_tau_s);
      const double chain =
          c.factor * (j < m ? map_->Derivative(j, z[j]) : experiment_->start_sigma_Pa[j - m]);
      for (long i = 0; i < static_cast<long>(column.size()); ++i) {
        jacobian[(row + i) * cols + j] = chain * column[i];
      }
    }
  }

  const Parameters* base_;
  const ParameterMap* map_;
  const FitExperiment* experiment_;
  const SimulationOptions* simulation_;
  JacobianMethod method_;
  // Ceres never evaluates one block from two threads at once.
  mutable EvaluationCache cache_;
  mutable std::vector<double> last_z_;  // of the last residual evaluation
  mutable Eigen::VectorXd last_residuals_;
  mutable double first_cost_ = NAN;
};

// Each fitted run at `params` with its weighted residuals (NaN where it
// cannot be simulated): whole, simulated from its logged start, or cut into
// the windows of multiple shooting (Windows), each from its logged state.
// With max_runs > 0, at most that many of them (SubsetByHash), in their order.
struct RunResiduals {
  FitExperiment run;
  Eigen::VectorXd residuals;
};
std::vector<RunResiduals> FittedRunResiduals(const Parameters& params, const Unit& unit,
                                             const FitSpec& spec, const RefineOptions& options,
                                             bool windows, std::size_t max_runs = 0);

// FittedRunResiduals' runs at `params`, prepared once and simulated one at a
// time on request, so a caller can stop early (WindowedMeasure). `options`
// must outlive it (its simulation options are used, not copied).
class FittedRunSet {
 public:
  FittedRunSet(const Parameters& params, const Unit& unit, const FitSpec& spec,
               const RefineOptions& options, bool windows, std::size_t max_runs = 0);

  const std::vector<FitExperiment>& runs() const { return runs_; }
  // Run k's weighted residuals (NaN where it cannot be simulated); with
  // `use`, what its simulation read of the friction.
  Eigen::VectorXd Residuals(std::size_t k, FrictionUse* use = nullptr) const;
  // The set the runs are simulated with: the rig's conditions, the free
  // parameters through the bounds map (as the residual blocks see them).
  Parameters Simulated() const { return WithValues(conditioned_, map_, theta_.data()); }
  // The runs, handed over: the set has none left to simulate.
  std::vector<FitExperiment> ReleaseRuns() { return std::move(runs_); }

 private:
  const Parameters conditioned_;
  const ParameterMap map_;
  const std::vector<double> theta_;
  const SimulationOptions& simulation_;
  const JacobianMethod jacobian_;
  std::vector<FitExperiment> runs_;
};

// How many of `n` indices SubsetByHash keeps: all when count is 0 or >= n,
// else `count`.
inline std::size_t SubsetSize(std::size_t n, std::size_t count) {
  return count == 0 ? n : std::min(n, count);
}

// Which SubsetSize(n, count) of `n` indices to keep: those whose fixed hash
// (splitmix64 of the index) ranks lowest. Deterministic, the same for every
// call, and without the period of an every-k-th stride.
std::vector<bool> SubsetByHash(std::size_t n, std::size_t count);

// FittedRunResiduals of the whole runs.
inline std::vector<RunResiduals> WholeRunResiduals(const Parameters& params, const Unit& unit,
                                                   const FitSpec& spec,
                                                   const RefineOptions& options) {
  return FittedRunResiduals(params, unit, spec, options, false);
}

// 0.5 |r|^2 of each run (NaN where it could not be simulated), as both the
// start's and the fit's cost.
std::vector<ExperimentCost> CostsOf(const std::vector<RunResiduals>& runs);

// CostsOf the whole fitted runs at `params` from their logged starts: what a
// windowed stage's costs are reported as.
std::vector<ExperimentCost> WholeRunCosts(const Parameters& params, const Unit& unit,
                                          const FitSpec& spec, const RefineOptions& options);

}  // namespace pneumaid::refine_internal
