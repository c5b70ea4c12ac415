#include "pneumaid/ident/refine.h"

#include <ceres/ceres.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <numeric>
#include <random>
#include <sstream>

#include "pneumaid/eval/metrics.h"
#include "pneumaid/ident/friction_fit.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/model/parameter_table.h"
#include "pneumaid/sim/sensitivities.h"

namespace pneumaid {
namespace {

std::string ManifestPath(const Unit& unit) { return unit.directory + "/unit.yaml"; }

// ---------------------------------------------------------------- parameters

// The solver's coordinates theta for the free parameters. Each parameter's
// scale coordinate w (w = p for a linear scale, w = ln p for a log scale) is
// mapped onto its bounds by a logistic function,
//   w = w_lo + (w_hi - w_lo) / (1 + exp(-theta)),
// so the problem Ceres sees is unconstrained: no step is ever rejected for
// leaving the bounds, and no projected line search (which would evaluate a
// Jacobian, a sensitivity run, at every trial point) is needed. Near a lower
// bound of 0 a linear parameter moves multiplicatively, like a log scale.
struct ParameterMap {
  std::vector<FreeParameter> free;

  bool IsLog(int j) const { return free[j].scale == ParameterScale::kLog; }
  double Low(int j) const { return IsLog(j) ? std::log(free[j].lower) : free[j].lower; }
  double Span(int j) const { return (IsLog(j) ? std::log(free[j].upper) : free[j].upper) - Low(j); }
  static double Logistic(double theta) { return 1.0 / (1.0 + std::exp(-theta)); }

  double ToValue(int j, double theta) const {
    const double w = Low(j) + Span(j) * Logistic(theta);
    return IsLog(j) ? std::exp(w) : w;
  }
  double ToTheta(int j, double value) const {
    const double w = IsLog(j) ? std::log(value) : value;
    // A start on a bound is moved just inside (theta would be infinite).
    const double f = std::clamp((w - Low(j)) / Span(j), 1e-9, 1.0 - 1e-9);
    return std::log(f / (1.0 - f));
  }
  double Derivative(int j, double theta) const {  // dp/dtheta
    const double s = Logistic(theta);
    const double dw = Span(j) * s * (1.0 - s);
    return IsLog(j) ? ToValue(j, theta) * dw : dw;
  }
  // The coordinates of the free parameters' values in `params`.
  std::vector<double> ThetaOf(const Parameters& params) const {
    std::vector<double> theta;
    for (int j = 0; j < size(); ++j) {
      double value = 0;
      GetParameter(params, free[j].path, &value);
      theta.push_back(ToTheta(j, value));
    }
    return theta;
  }
  int size() const { return static_cast<int>(free.size()); }
};

ParameterMap MakeParameterMap(const Parameters& start, const FitSpec& spec) {
  ParameterMap map;
  map.free = spec.parameters;
  for (const FreeParameter& p : spec.parameters) {
    double value = 0;
    if (!GetParameter(start, p.path, &value)) {
      throw InputError(spec.source, 0, 0,
                       "parameter " + p.path + " is not in the starting parameter set");
    }
    if (!(value >= p.lower && value <= p.upper)) {
      throw InputError(spec.source, 0, 0,
                       "the start value of " + p.path + " (" + std::to_string(value) +
                           ") lies outside its bounds");
    }
  }
  return map;
}

Parameters WithValues(const Parameters& base, const ParameterMap& map, const double* theta) {
  Parameters p = base;
  for (int j = 0; j < map.size(); ++j) SetParameter(&p, map.free[j].path, map.ToValue(j, theta[j]));
  return p;
}

// --------------------------------------------------------------- experiments

struct Channel {
  std::string name;
  std::vector<double> Trajectory::*values;
  Eigen::MatrixXd TrajectorySensitivities::*derivatives;
  double factor;       // weight / sigma
  double meter_tau_s;  // flows: the declared meter lag, 0 when none
};

// Nuisance coordinates of an estimated start: the offsets of p1(t0), p2(t0)
// from their logged values in units of their standard errors (0: as logged).
constexpr int kStartOffsets = kInitialPressureColumns;
using StartOffsets = std::array<double, kStartOffsets>;

struct FitExperiment {
  std::string id;
  Trajectory measured;
  CommandSignal command;
  InitialState initial;
  std::vector<Channel> channels;
  std::string parent;  // a window's run (multiple shooting); empty for a whole run
  // Standard errors of the logged initial p1, p2 [Pa] when they are estimated
  // (FitSpec::fit_initial_pressures); {0, 0}: the start is taken as logged.
  std::array<double, kStartOffsets> start_sigma_Pa = {0, 0};

  bool FitsStart() const { return start_sigma_Pa[0] > 0; }
  // Data rows, then one prior row per estimated initial pressure.
  long residuals() const {
    return static_cast<long>(measured.size() * channels.size()) + (FitsStart() ? kStartOffsets : 0);
  }
};

// The coordinates z of an experiment's residual block: the free parameters'
// theta, then its start offsets when it FitsStart (`offsets` unused otherwise).
std::vector<double> Coordinates(const FitExperiment& e, const double* theta, int m,
                                const double* offsets) {
  std::vector<double> z(theta, theta + m);
  if (e.FitsStart()) z.insert(z.end(), offsets, offsets + kStartOffsets);
  return z;
}

// The run's start with the offsets applied.
InitialState StartOf(const FitExperiment& e, const double* offsets) {
  InitialState initial = e.initial;
  if (e.FitsStart()) {
    initial.p1_Pa += offsets[0] * e.start_sigma_Pa[0];
    initial.p2_Pa += offsets[1] * e.start_sigma_Pa[1];
  }
  return initial;
}

const Channel kChannelTable[] = {
    {"x", &Trajectory::x_m, &TrajectorySensitivities::x, 0, 0},
    {"p1", &Trajectory::p1_Pa, &TrajectorySensitivities::p1, 0, 0},
    {"p2", &Trajectory::p2_Pa, &TrajectorySensitivities::p2, 0, 0},
    {"q1", &Trajectory::q1_kg_per_s, &TrajectorySensitivities::q1, 0, 0},
    {"q2", &Trajectory::q2_kg_per_s, &TrajectorySensitivities::q2, 0, 0}};

bool IsSimulable(const Experiment& e) {
  return e.entry.kind == ExperimentKind::kStroke || e.entry.kind == ExperimentKind::kValidation;
}

// Experiments named by id or kind; InputError for a name that matches none.
std::vector<const Experiment*> Select(const Unit& unit, const std::vector<std::string>& names,
                                      const FitSpec& spec, bool must_match) {
  std::vector<const Experiment*> chosen;
  for (const std::string& name : names) {
    bool matched = false;
    for (const Experiment& e : unit.experiments) {
      const bool by_kind = name == ToString(e.entry.kind);
      if (!by_kind && e.entry.id != name) continue;
      matched = true;
      if (!IsSimulable(e)) {
        if (by_kind) continue;
        throw InputError(spec.source, 0, 0,
                         "experiment '" + name + "' is a " + ToString(e.entry.kind) +
                             " log; only stroke and validation runs can be refined on");
      }
      if (std::find(chosen.begin(), chosen.end(), &e) == chosen.end()) chosen.push_back(&e);
    }
    const bool is_kind = name == "stroke" || name == "validation";
    if (!matched && (must_match || !is_kind)) {
      throw InputError(spec.source, 0, 0,
                       "no experiment or kind '" + name + "' in " + ManifestPath(unit));
    }
  }
  return chosen;
}

// A channel's noise sigma [SI]: the spec's when it gives one, else the one
// declared under the manifest's `sensors` (0 when neither does).
double ChannelSigma(const FitSpec& spec, const Unit& unit, const std::string& channel) {
  const auto given = spec.channels.find(channel);
  return given != spec.channels.end() && given->second.sigma > 0
             ? given->second.sigma
             : unit.manifest.DeclaredSigma(channel, 0.0);
}

// The noise sigmas of one logged sample of p1 and p2, when the spec estimates
// starts and both are known; {0, 0} (the start is taken as logged) otherwise.
std::array<double, kStartOffsets> StartSampleSigma(const FitSpec& spec, const Unit& unit) {
  const double p1 = ChannelSigma(spec, unit, "p1"), p2 = ChannelSigma(spec, unit, "p2");
  if (!spec.fit_initial_pressures || !(p1 > 0 && p2 > 0)) return {0, 0};
  return {p1, p2};
}

// `sample_sigma_Pa`: StartSampleSigma(spec, unit).
FitExperiment Prepare(const Experiment& e, const Unit& unit, const FitSpec& spec,
                      double half_stroke_m,
                      const std::array<double, kStartOffsets>& sample_sigma_Pa) {
  FitExperiment out;
  out.id = e.entry.id;
  out.measured = e.AsTrajectory();
  out.command = SampledCommand(out.measured.t_s, out.measured.u_V);
  int averaged = 1;
  out.initial = LoggedInitialState(out.measured, half_stroke_m, &averaged);
  const double root_n = std::sqrt(static_cast<double>(averaged));
  for (int k = 0; k < kStartOffsets; ++k) out.start_sigma_Pa[k] = sample_sigma_Pa[k] / root_n;
  for (const Channel& row : kChannelTable) {
    const auto wanted = spec.channels.find(row.name);
    if (wanted == spec.channels.end() || (out.measured.*row.values).empty()) continue;
    const double sigma = ChannelSigma(spec, unit, row.name);
    if (!(sigma > 0)) {
      throw InputError(spec.source, 0, 0,
                       "channel " + row.name +
                           ": no sigma given and none declared under sensors "
                           "in " +
                           ManifestPath(unit));
    }
    Channel c = row;
    c.factor = wanted->second.weight / sigma;
    c.meter_tau_s = row.name[0] == 'q' ? unit.manifest.DeclaredTau(row.name, 0.0) : 0.0;
    out.channels.push_back(c);
  }
  if (out.channels.empty()) {
    throw InputError(spec.source, 0, 0, "experiment '" + out.id + "' logs none of the channels");
  }
  return out;
}

// A stuck phase: the logged position stays within the band for at least this
// many samples; a window is at least this long.
constexpr std::size_t kMinStuckSamples = 5;
constexpr std::size_t kMinWindowSamples = 20;

// Samples [begin, end) of a run as a trajectory.
Trajectory Slice(const Trajectory& run, std::size_t begin, std::size_t end) {
  Trajectory out;
  const auto cut = [&](const std::vector<double>& from, std::vector<double>* to) {
    if (!from.empty()) to->assign(from.begin() + begin, from.begin() + end);
  };
  cut(run.t_s, &out.t_s);
  cut(run.u_V, &out.u_V);
  cut(run.x_m, &out.x_m);
  cut(run.v_m_per_s, &out.v_m_per_s);
  cut(run.p1_Pa, &out.p1_Pa);
  cut(run.p2_Pa, &out.p2_Pa);
  cut(run.q1_kg_per_s, &out.q1_kg_per_s);
  cut(run.q2_kg_per_s, &out.q2_kg_per_s);
  return out;
}

// Multiple shooting (FitStage::windows): the run cut where the rod is stuck,
// each window simulated from its logged state, v = 0, with the command-driven
// lags replayed from the start of the log. `band_m`: how far a stuck rod's
// logged position may wander (noise and ADC step).
std::vector<FitExperiment> Windows(const FitExperiment& run, double band_m, double half_stroke_m,
                                   const std::array<double, kStartOffsets>& sample_sigma_Pa) {
  const std::vector<double>& x = run.measured.x_m;
  const std::size_t n = x.size();
  std::vector<std::size_t> starts = {0};
  std::vector<double> rest_positions = {run.initial.position_m};
  for (std::size_t i = 1; i < n;) {
    std::size_t j = i;
    while (j + 1 < n && std::fabs(x[j + 1] - x[i]) <= band_m) ++j;
    if (j - i + 1 >= kMinStuckSamples && i - starts.back() >= kMinWindowSamples &&
        n - i >= kMinWindowSamples) {
      starts.push_back(i);
      double sum = 0;
      for (std::size_t k = i; k < i + kMinStuckSamples; ++k) sum += x[k];
      rest_positions.push_back(sum / kMinStuckSamples);
    }
    i = j + 1;
  }
  std::vector<FitExperiment> windows;
  for (std::size_t w = 0; w < starts.size(); ++w) {
    const std::size_t begin = starts[w], end = w + 1 < starts.size() ? starts[w + 1] : n;
    FitExperiment window = run;
    window.measured = Slice(run.measured, begin, end);
    window.id = run.id + "@" + std::to_string(run.measured.t_s[begin]);
    window.parent = run.id;
    if (begin > 0) {
      window.initial = InitialState{};
      window.initial.position_m = std::clamp(rest_positions[w], -half_stroke_m, half_stroke_m);
      window.initial.p1_Pa = run.measured.p1_Pa[begin];
      window.initial.p2_Pa = run.measured.p2_Pa[begin];
      window.initial.lag_history_from_s = run.measured.t_s.front();
      if (run.FitsStart()) window.start_sigma_Pa = sample_sigma_Pa;  // one sample each
    }
    windows.push_back(std::move(window));
  }
  return windows;
}

// ------------------------------------------------------------------ residuals

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
    // the step, residuals and Jacobian at the same point: the plain run is
    // not repeated.
    const bool known =
        jacobian != nullptr && last_residuals_.size() == num_residuals() && z == last_z_;
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
  bool Residuals(const double* z, double* residuals) const {
    const Parameters params = WithValues(*base_, *map_, z);
    if (!Validate(params).empty()) return false;
    const FitExperiment& e = *experiment_;
    Trajectory sim;
    const SimulationSummary summary = Simulate(params, e.command, StartOf(e, z + map_->size()),
                                               e.measured.t_s, *simulation_, &sim);
    if (!summary.ok() || sim.size() != e.measured.size()) return false;
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

// ------------------------------------------------------------------- solving

// Latin-hypercube points inside the bounds: each parameter's range (in its
// scale coordinate) cut into `count` strata, one point per stratum, strata
// shuffled per axis.
std::vector<std::vector<double>> LatinHypercube(const ParameterMap& map, int count,
                                                std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<std::vector<double>> points(count, std::vector<double>(map.size()));
  for (int j = 0; j < map.size(); ++j) {
    std::vector<int> strata(count);
    std::iota(strata.begin(), strata.end(), 0);
    std::shuffle(strata.begin(), strata.end(), random);
    for (int k = 0; k < count; ++k) {
      // Uniform in the scale coordinate (p, or ln p), not in theta.
      const double fraction = (strata[k] + unit(random)) / count;
      const double w = map.Low(j) + map.Span(j) * fraction;
      points[k][j] = map.ToTheta(j, map.IsLog(j) ? std::exp(w) : w);
    }
  }
  return points;
}

struct Problem {
  ceres::Problem problem;
  std::vector<double> theta;
  std::vector<StartOffsets> offsets;              // per experiment (used when it FitsStart)
  std::vector<const ExperimentResidual*> blocks;  // owned by problem
};

// J^T J of the free parameters from one experiment's Jacobian, its start
// offsets (the last columns, when estimated) eliminated: the Schur complement
// A^T A - A^T B (B^T B)^-1 B^T A, so their uncertainty widens the parameters'.
Eigen::MatrixXd ParameterInformation(const EvaluationCache& at, int m) {
  const auto a = at.jacobian.leftCols(m);
  Eigen::MatrixXd information = a.transpose() * a;
  if (at.jacobian.cols() == m) return information;
  const auto b = at.jacobian.rightCols(at.jacobian.cols() - m);
  const Eigen::MatrixXd cross = a.transpose() * b;
  const Eigen::MatrixXd start = b.transpose() * b;  // >= identity: the priors
  information -= cross * start.ldlt().solve(cross.transpose());
  return information;
}

// Stops a start once its cost has improved by less than stall_tolerance
// (relative) over its last stall_iterations accepted steps, or after two
// rejected steps in a row once it has moved. The
// cost of an event-driven model is rough at about 1e-3 relative: each
// stick/slip switch is located to the integrator's tolerance, so the
// trajectories (and the cost) jitter at that level, far inside the
// parameters' confidence region. Levenberg-Marquardt otherwise keeps trying
// steps against that jitter until its radius collapses.
class StallCallback final : public ceres::IterationCallback {
 public:
  StallCallback(int iterations, double tolerance) : window_(iterations), tolerance_(tolerance) {}

  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override {
    if (summary.iteration == 0) {
      accepted_.push_back(summary.cost);
      return ceres::SOLVER_CONTINUE;
    }
    if (!summary.step_is_successful) {
      // Rejected steps shrink the trust region; once the start has moved, a
      // run of them means the cost's jitter, not the model, limits progress.
      return accepted_.size() > 1 && ++rejected_in_a_row_ >= kMaxRejectedInARow
                 ? ceres::SOLVER_TERMINATE_SUCCESSFULLY
                 : ceres::SOLVER_CONTINUE;
    }
    rejected_in_a_row_ = 0;
    accepted_.push_back(summary.cost);
    const size_t n = accepted_.size();
    if (n > static_cast<size_t>(window_)) {
      const double before = accepted_[n - 1 - static_cast<size_t>(window_)];
      if (before - accepted_.back() < tolerance_ * before) {
        return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
      }
    }
    return ceres::SOLVER_CONTINUE;
  }

 private:
  static constexpr int kMaxRejectedInARow = 2;
  int window_;
  double tolerance_;
  int rejected_in_a_row_ = 0;
  std::vector<double> accepted_;  // cost after each accepted step (and at the start)
};

ceres::Solver::Options SolverOptions(const FitSpec& spec, const RefineOptions& options) {
  ceres::Solver::Options s;
  s.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  s.linear_solver_type = ceres::DENSE_QR;
  s.max_num_iterations = spec.max_iterations;
  s.num_threads = options.threads;
  s.function_tolerance = options.function_tolerance;
  s.minimizer_progress_to_stdout = options.verbose;
  s.logging_type = options.verbose ? ceres::PER_MINIMIZER_ITERATION : ceres::SILENT;
  return s;
}

// Covariance of the free parameters at the optimum, in their SI units, from
// the Gauss-Newton approximation (J^T J)^-1 (a pseudo-inverse: a direction
// the data do not determine gets no finite variance but no crash either),
// inflated by the reduced chi-square when the model misses the data by more
// than the declared noise (the honest reading of a misfit), plus the fit's
// numerical resolution: the cost of the event-driven model jitters at
// `cost_resolution` (relative), so every point whose cost lies within
// cost_resolution x cost of the minimum is as good a stop as any; along
// parameter j that band reaches sqrt(2 cost_resolution cost (J^T J)^-1_jj).
// Without that term the errors were 5 to 20 times smaller than the distance
// to the truth on synthetic units. `normal` is J^T J of the free parameters
// with any estimated starts eliminated. Empty on failure.
Eigen::MatrixXd ParameterCovariance(const Eigen::MatrixXd& normal, const ParameterMap& map,
                                    const std::vector<double>& theta, double cost, long residuals,
                                    double cost_resolution) {
  const int m = map.size();
  if (normal.rows() != m) return {};
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(normal);
  if (eigen.info() != Eigen::Success) return {};
  const Eigen::VectorXd values = eigen.eigenvalues();
  Eigen::VectorXd inverse = Eigen::VectorXd::Zero(m);
  const double floor = 1e-14 * values.maxCoeff();
  for (int i = 0; i < m; ++i) inverse[i] = values[i] > floor ? 1.0 / values[i] : 0.0;
  const Eigen::MatrixXd theta_cov =
      eigen.eigenvectors() * inverse.asDiagonal() * eigen.eigenvectors().transpose();
  const double dof = std::max(1.0, static_cast<double>(residuals - m));
  const double inflation = std::max(1.0, 2.0 * cost / dof) + 2.0 * cost_resolution * cost;
  Eigen::VectorXd d(m);
  for (int j = 0; j < m; ++j) d[j] = map.Derivative(j, theta[j]);
  return inflation * (d.asDiagonal() * theta_cov * d.asDiagonal());
}

void Summarise(const Eigen::MatrixXd& cov, const ParameterMap& map, const RefineOptions& options,
               RefineResult* r) {
  const int m = map.size();
  if (cov.rows() != m) return;
  r->correlation = Eigen::MatrixXd::Identity(m, m);
  for (int i = 0; i < m; ++i) {
    r->parameters[i].standard_error = std::sqrt(std::max(0.0, cov(i, i)));
    r->params.uncertainty[map.free[i].path] = r->parameters[i].standard_error;
    for (int j = 0; j < i; ++j) {
      const double denominator = std::sqrt(cov(i, i) * cov(j, j));
      const double rho = denominator > 0 ? cov(i, j) / denominator : 0.0;
      r->correlation(i, j) = r->correlation(j, i) = rho;
      if (std::fabs(rho) > options.correlation_flag) {
        r->poorly_separable.emplace_back(map.free[j].path, map.free[i].path);
        r->poorly_separable_correlation.push_back(rho);
      }
    }
  }
}

ValidationReport HeldOut(const Parameters& params, const Unit& unit,
                         const std::vector<const Experiment*>& held_out,
                         const RefineOptions& options) {
  if (held_out.empty()) return {};
  ValidationOptions v;
  v.simulation = options.validation;
  for (const Experiment* e : held_out) v.experiment_ids.push_back(e->entry.id);
  return ValidateUnit(params, unit, v);
}

std::string AppendProvenance(const std::string& provenance, const RefineResult& r,
                             const FitSpec& spec) {
  std::ostringstream entry;
  entry << "refine: {spec: \"" << spec.source << "\", cost_before: " << r.cost_before
        << ", cost_after: " << r.cost_after << ", iterations: " << r.iterations
        << ", stages: " << r.stages << ", starts: " << r.starts
        << ", experiments: " << r.fitted.size()
        << ", initial_pressures: " << (spec.fit_initial_pressures ? "fit" : "logged")
        << ", converged: " << (r.converged ? "true" : "false") << "}";
  const std::size_t close = provenance.rfind('}');
  if (provenance.empty() || close == std::string::npos) return "{" + entry.str() + "}";
  const bool empty = provenance.find_first_not_of("{} \n") == std::string::npos;
  return provenance.substr(0, close) + (empty ? "" : ", ") + entry.str() + "}";
}

}  // namespace

bool RefineOptions::IsValid(std::string* error) const {
  const auto fail = [error](const char* what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (threads < 1) return fail("threads must be >= 1");
  if (!(function_tolerance > 0)) return fail("function_tolerance must be > 0");
  if (stall_iterations < 1) return fail("stall_iterations must be >= 1");
  if (!(stall_tolerance >= 0)) return fail("stall_tolerance must be >= 0");
  if (!(earlier_stage_stall_tolerance >= 0))
    return fail("earlier_stage_stall_tolerance must be >= 0");
  if (!(correlation_flag > 0 && correlation_flag < 1)) {
    return fail("correlation_flag must be in (0, 1)");
  }
  return simulation.IsValid(error);
}

namespace {

// One Levenberg-Marquardt fit of spec.parameters (all starts); held-out
// validation and provenance are the caller's.
// The fitted runs of a spec, whole or cut into windows.
std::vector<FitExperiment> FittedRuns(const Parameters& conditioned, const Unit& unit,
                                      const FitSpec& spec, bool windows) {
  const auto fitted = Select(unit, spec.fit, spec, true);
  for (const Experiment* e : Select(unit, spec.hold_out, spec, false)) {
    if (std::count(fitted.begin(), fitted.end(), e)) {
      throw InputError(spec.source, 0, 0,
                       "experiment '" + e->entry.id + "' is both fitted and held out");
    }
  }
  if (fitted.empty()) throw InputError(spec.source, 0, 0, "no experiment to fit");
  const double half_stroke = 0.5 * conditioned.cylinder.stroke_m;
  const double band = 4.0 * unit.manifest.DeclaredSigma("x", 5e-6) + 10e-6;
  const std::array<double, kStartOffsets> sample_sigma = StartSampleSigma(spec, unit);
  std::vector<FitExperiment> runs;
  for (const Experiment* e : fitted) {
    FitExperiment run = Prepare(*e, unit, spec, half_stroke, sample_sigma);
    if (!windows) {
      runs.push_back(std::move(run));
      continue;
    }
    for (FitExperiment& window : Windows(run, band, half_stroke, sample_sigma)) {
      runs.push_back(std::move(window));
    }
  }
  return runs;
}

// Windows' costs summed per run, in the order the runs first appear.
std::vector<ExperimentCost> PerRun(const std::vector<ExperimentCost>& costs,
                                   const std::vector<FitExperiment>& runs) {
  std::vector<ExperimentCost> merged;
  for (size_t k = 0; k < costs.size(); ++k) {
    const std::string& id = runs[k].parent.empty() ? runs[k].id : runs[k].parent;
    if (merged.empty() || merged.back().id != id) merged.push_back({id, 0, 0, 0});
    merged.back().before += costs[k].before;
    merged.back().after += costs[k].after;
    merged.back().residuals += costs[k].residuals;
  }
  return merged;
}

// 0.5 |r|^2 of each whole fitted run at `params` from its logged start (NaN
// where it cannot be simulated): what a windowed stage's costs are reported as.
std::vector<ExperimentCost> WholeRunCosts(const Parameters& params, const Unit& unit,
                                          const FitSpec& spec, const RefineOptions& options) {
  const Parameters conditioned = WithRigConditions(params, unit);
  const ParameterMap map = MakeParameterMap(conditioned, spec);
  const std::vector<double> theta = map.ThetaOf(conditioned);
  std::vector<ExperimentCost> costs;
  for (const FitExperiment& run : FittedRuns(conditioned, unit, spec, false)) {
    const ExperimentResidual residual(&conditioned, &map, &run, &options.simulation,
                                      options.jacobian);
    std::vector<double> r(static_cast<size_t>(residual.num_residuals()));
    const StartOffsets as_logged = {0, 0};
    const double* blocks[] = {theta.data(), as_logged.data()};
    const double cost =
        residual.Evaluate(blocks, r.data(), nullptr)
            ? 0.5 * Eigen::Map<Eigen::VectorXd>(r.data(), static_cast<Eigen::Index>(r.size()))
                        .squaredNorm()
            : NAN;
    costs.push_back({run.id, cost, cost, run.residuals()});
  }
  return costs;
}

// Counts an estimated start and keeps the largest move of its pressures.
void RecordStartOffset(const FitExperiment& e, const StartOffsets& offsets, RefineResult* r) {
  ++r->estimated_starts;
  for (int k = 0; k < kStartOffsets; ++k) {
    if (std::fabs(offsets[k]) > r->largest_start_offset_sigma) {
      r->largest_start_offset_sigma = std::fabs(offsets[k]);
      r->largest_start_offset_Pa = std::fabs(offsets[k]) * e.start_sigma_Pa[k];
    }
  }
}

RefineResult RefineStage(const Parameters& start, const Unit& unit, const FitSpec& spec,
                         bool windows, bool last, const RefineOptions& options) {
  const Parameters conditioned = WithRigConditions(start, unit);
  const ParameterMap map = MakeParameterMap(conditioned, spec);
  const std::vector<FitExperiment> experiments = FittedRuns(conditioned, unit, spec, windows);

  Problem p;
  p.theta = map.ThetaOf(conditioned);
  p.offsets.assign(experiments.size(), StartOffsets{0, 0});  // never reallocated below
  long data_rows = 0;  // residuals less the start priors (one per start offset)
  for (size_t k = 0; k < experiments.size(); ++k) {
    const FitExperiment& e = experiments[k];
    auto* block =
        new ExperimentResidual(&conditioned, &map, &e, &options.simulation, options.jacobian);
    if (e.FitsStart()) {
      p.problem.AddResidualBlock(block, nullptr, p.theta.data(), p.offsets[k].data());
    } else {
      p.problem.AddResidualBlock(block, nullptr, p.theta.data());
    }
    p.blocks.push_back(block);
    data_rows += e.residuals() - (e.FitsStart() ? kStartOffsets : 0);
  }

  RefineResult r;
  const std::vector<double> start_theta = p.theta;
  std::vector<std::vector<double>> starts = {start_theta};
  for (auto& point : LatinHypercube(map, spec.multistart, spec.seed)) starts.push_back(point);

  ceres::Solver::Options solver = SolverOptions(spec, options);
  const long start_columns = std::count_if(experiments.begin(), experiments.end(),
                                           [](const FitExperiment& e) { return e.FitsStart(); }) *
                             kStartOffsets;
  if (start_columns > map.size()) {
    // Dense QR's work grows with the square of the columns (two per window
    // of a windowed stage): eliminate the start offsets, each of which
    // touches one experiment (Schur complement), instead.
    solver.linear_solver_type = ceres::DENSE_SCHUR;
  }
  double best_cost = INFINITY;
  std::vector<double> best_theta = start_theta;
  std::vector<StartOffsets> best_offsets = p.offsets;
  for (size_t s = 0; s < starts.size(); ++s) {
    p.theta = starts[s];
    std::fill(p.offsets.begin(), p.offsets.end(), StartOffsets{0, 0});  // as logged
    // A stage before the last only prepares the next one's start, which
    // refits its parameters anyway: it stops at the first small gain.
    StallCallback stall(last ? options.stall_iterations : 1,
                        last ? options.stall_tolerance : options.earlier_stage_stall_tolerance);
    ceres::Solver::Options start_options = solver;
    start_options.callbacks.push_back(&stall);
    ceres::Solver::Summary summary;
    ceres::Solve(start_options, &p.problem, &summary);
    if (options.verbose) std::cout << summary.FullReport() << "\n";
    r.iterations += static_cast<int>(summary.iterations.size());
    if (summary.IsSolutionUsable() && summary.final_cost < best_cost) {
      best_cost = summary.final_cost;
      best_theta = p.theta;
      best_offsets = p.offsets;
      r.best_start = static_cast<int>(s);
      r.converged = summary.termination_type == ceres::CONVERGENCE ||
                    summary.termination_type == ceres::USER_SUCCESS;
      r.message = summary.message;
    } else if (!std::isfinite(best_cost)) {
      r.message = summary.message;
    }
  }
  r.starts = static_cast<int>(starts.size());
  for (size_t k = 0; k < experiments.size(); ++k) {
    // Ceres' first evaluation is at the given start.
    r.fitted.push_back(
        {experiments[k].id, p.blocks[k]->FirstCost(), 0, experiments[k].residuals()});
    r.cost_before += r.fitted.back().before;
  }
  p.theta = best_theta;
  p.offsets = best_offsets;
  if (!std::isfinite(best_cost)) {
    r.converged = false;
    r.params = start;
    r.message = "no start gave a usable solution: " + r.message;
  } else {
    r.params = WithValues(conditioned, map, p.theta.data());
    Eigen::MatrixXd normal = Eigen::MatrixXd::Zero(map.size(), map.size());
    for (size_t k = 0; k < experiments.size(); ++k) {
      const EvaluationCache* at_best = nullptr;
      const std::vector<double> z =
          Coordinates(experiments[k], p.theta.data(), map.size(), p.offsets[k].data());
      if (!p.blocks[k]->ResidualsAndJacobian(z, &at_best)) {
        normal.resize(0, 0);
        r.fitted[k].after = NAN;
        continue;
      }
      r.fitted[k].after = 0.5 * at_best->residuals.squaredNorm();
      r.cost_after += r.fitted[k].after;
      if (normal.size() > 0) normal += ParameterInformation(*at_best, map.size());
      if (experiments[k].FitsStart()) RecordStartOffset(experiments[k], p.offsets[k], &r);
    }
    for (int j = 0; j < map.size(); ++j) {
      RefinedParameter rp;
      rp.path = map.free[j].path;
      GetParameter(conditioned, rp.path, &rp.start);
      rp.value = map.ToValue(j, p.theta[j]);
      const double span = map.free[j].upper - map.free[j].lower;
      rp.at_bound =
          std::min(rp.value - map.free[j].lower, map.free[j].upper - rp.value) < 1e-6 * span;
      r.parameters.push_back(rp);
    }
    Summarise(
        ParameterCovariance(normal, map, p.theta, r.cost_after, data_rows, options.stall_tolerance),
        map, options, &r);
  }
  if (windows) r.fitted = PerRun(r.fitted, experiments);
  return r;
}

// FitStage::friction_replay: the identification's friction fit on the
// stroke logs, from the current friction; directions without slides keep it.
void ReplayFriction(const Unit& unit, Parameters* params, std::string* report) {
  const FrictionFitResult fit = FitFriction(unit, params->friction, FrictionFitOptions{});
  *report += fit.BriefReport();
  if (!fit.fitted) return;
  if (fit.positive.fitted) params->friction.positive = fit.positive.params;
  if (fit.negative.fitted) params->friction.negative = fit.negative.params;
}

// The spec of one stage: its parameters only, in the order of `parameters`.
FitSpec StageSpec(const FitSpec& spec, const FitStage& stage) {
  FitSpec one = spec;
  one.stages.clear();
  if (stage.parameters.empty()) return one;  // all
  one.parameters.clear();
  for (const FreeParameter& p : spec.parameters) {
    if (std::count(stage.parameters.begin(), stage.parameters.end(), p.path)) {
      one.parameters.push_back(p);
    }
  }
  return one;
}

}  // namespace

RefineResult Refine(const Parameters& start, const Unit& unit, const FitSpec& spec,
                    const RefineOptions& options) {
  const auto clock = std::chrono::steady_clock::now();
  std::string error;
  if (!options.IsValid(&error)) throw InputError("refine options", 0, 0, error);
  const std::vector<FitStage> stages =
      spec.stages.empty() ? std::vector<FitStage>{FitStage{}} : spec.stages;
  RefineResult r;
  Parameters current = start;
  int iterations = 0;
  std::vector<ExperimentCost> before;
  double cost_before = 0;
  bool first_fit = true;
  for (size_t k = 0; k < stages.size(); ++k) {
    if (stages[k].friction_replay) {
      ReplayFriction(unit, &current, &r.replay_report);
      continue;
    }
    const std::string replay_report = r.replay_report;
    r = RefineStage(current, unit, StageSpec(spec, stages[k]), stages[k].windows,
                    k + 1 == stages.size(), options);
    r.replay_report = replay_report;
    iterations += r.iterations;
    if (first_fit) {
      before = r.fitted;
      cost_before = r.cost_before;
      first_fit = false;
    }
    if (r.parameters.empty()) {
      r.message = "stage " + std::to_string(k + 1) + ": " + r.message;
      break;
    }
    current = r.params;
  }
  r.iterations = iterations;
  // A windowed stage's costs are windows': report whole runs, as validated
  // (and at the true start when friction was replayed first).
  if (stages.front().windows || stages.front().friction_replay) {
    before = WholeRunCosts(start, unit, spec, options);
    cost_before = 0;
    for (const ExperimentCost& e : before) cost_before += e.before;
  }
  if (stages.back().windows && !r.parameters.empty()) {
    r.fitted = WholeRunCosts(r.params, unit, spec, options);
    r.cost_after = 0;
    for (const ExperimentCost& e : r.fitted) r.cost_after += e.after;
  }
  r.cost_before = cost_before;
  for (size_t k = 0; k < r.fitted.size() && k < before.size(); ++k) {
    r.fitted[k].before = before[k].before;
  }
  const Parameters conditioned = WithRigConditions(start, unit);
  for (RefinedParameter& p : r.parameters) GetParameter(conditioned, p.path, &p.start);
  if (!r.parameters.empty()) {
    r.params.provenance_yaml = AppendProvenance(r.params.provenance_yaml, r, spec);
  }
  const auto held_out = Select(unit, spec.hold_out, spec, false);
  r.held_out_before = HeldOut(conditioned, unit, held_out, options);
  r.held_out_after =
      HeldOut(r.parameters.empty() ? conditioned : r.params, unit, held_out, options);
  r.stages = static_cast<int>(stages.size());
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock).count();
  return r;
}

std::string RefineResult::BriefReport() const {
  std::ostringstream out;
  char line[256];
  std::snprintf(line, sizeof(line),
                "Refinement: %s, cost %.6g -> %.6g, %d iterations in %d stage(s), %d start(s) "
                "(best: %d), %.2f s\n",
                converged ? "converged" : "NOT converged", cost_before, cost_after, iterations,
                stages, starts, best_start, wall_time_s);
  out << line;
  if (!converged && !message.empty()) out << "  " << message << "\n";
  if (!replay_report.empty()) out << "  friction replay stage: " << replay_report;
  if (estimated_starts > 0) {
    std::snprintf(line, sizeof(line),
                  "  initial pressures of %d run(s) estimated: largest move %.2g standard errors "
                  "(%.3g Pa) from the logged values\n",
                  estimated_starts, largest_start_offset_sigma, largest_start_offset_Pa);
    out << line;
  }
  for (const RefinedParameter& p : parameters) {
    std::snprintf(line, sizeof(line), "  %-28s %12.6g -> %12.6g +- %.3g%s\n", p.path.c_str(),
                  p.start, p.value, p.standard_error, p.at_bound ? "  (at a bound)" : "");
    out << line;
  }
  for (size_t i = 0; i < poorly_separable.size(); ++i) {
    out << "  poorly separable: " << poorly_separable[i].first << ", " << poorly_separable[i].second
        << " correlation " << poorly_separable_correlation[i] << "\n";
  }
  for (const ExperimentCost& e : fitted) {
    std::snprintf(line, sizeof(line), "  fitted   %-16s cost %.6g -> %.6g (%ld residuals)\n",
                  e.id.c_str(), e.before, e.after, e.residuals);
    out << line;
  }
  for (size_t i = 0; i < held_out_after.experiments.size(); ++i) {
    const auto& before = held_out_before.experiments[i];
    const auto& after = held_out_after.experiments[i];
    const auto rmse = [](const ExperimentValidation& e, const char* channel) {
      const auto found = e.channels.find(channel);
      return found == e.channels.end() ? NAN : found->second.rmse;
    };
    std::snprintf(line, sizeof(line),
                  "  held out %-16s x RMSE %.4g -> %.4g mm, p1 RMSE %.4g -> %.4g bar\n",
                  after.id.c_str(), rmse(before, "x") * 1e3, rmse(after, "x") * 1e3,
                  rmse(before, "p1") * 1e-5, rmse(after, "p1") * 1e-5);
    out << line;
  }
  return out.str();
}

}  // namespace pneumaid
