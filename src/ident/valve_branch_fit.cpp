#include "valve_branch_fit.h"

#include <ceres/ceres.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>

#include "pneumaid/model/kvp.h"
#include "quiet_solver.h"

namespace pneumaid::internal {
namespace {

const char* const kParameterNames[kBranchParameters] = {"q_max", "a", "b", "c", "d"};

// (K_vp(u; theta) - measured) / sigma for one plateau; theta = q_max, a, b, c, d.
struct PlateauResidual {
  double u_V, kvp, sigma, u_sat_V;

  template <typename T>
  bool operator()(const T* theta, T* residual) const {
    const KvpCoefficients<T> c{theta[1], theta[2], theta[3], theta[4], theta[0], T(u_sat_V)};
    residual[0] = (Kvp(T(u_V), c) - T(kvp)) / T(sigma);
    return true;
  }
};

// A staircase that stops below u_sat leaves q_max to the polynomial: the
// plateaus determine q_max poly(u) and K_vp is taken as continuous at u_sat,
// poly(u_sat) = 1, with this standard error (a prior on the one direction
// the plateaus leave open: the scale shared by q_max and the polynomial; the
// paper's branches jump by 0.6 % and 2.1 % there).
constexpr double kContinuitySigma = 0.03;
struct ContinuityResidual {
  double u_sat_V;

  template <typename T>
  bool operator()(const T* theta, T* residual) const {
    // poly(u_sat): the polynomial of K_vp with q_max 1.
    const KvpCoefficients<T> c{theta[1], theta[2], theta[3], theta[4], T(1.0), T(u_sat_V)};
    residual[0] = (KvpPolynomial(T(u_sat_V), c) - T(1.0)) / T(kContinuitySigma);
    return true;
  }
};

// q_max is read off the polynomial at u_sat only when the staircase reached
// this fraction of u_sat: from 0.45 V the paper valve's decreasing branch
// came out 10.8 % low (3.6 of its standard errors), from 0.6 V 3.3 % (1.1).
// Below it q_max is held at the prior's and the polynomial fitted to K_vp
// where the staircase went.
constexpr double kExtrapolationReach = 0.8;

KvpBranchParams Unpack(const double* theta, double u_sat_V) {
  return {theta[1], theta[2], theta[3], theta[4], theta[0], u_sat_V};
}

// Enough plateaus to determine the polynomial (four distinct openings below
// u_sat; q_max from the plateaus at or above it, else from the polynomial at
// u_sat)? Empty when so, else why not.
std::string Unidentifiable(const std::vector<const ValvePlateau*>& plateaus, double u_sat_V) {
  std::set<double> below;
  for (const auto* p : plateaus) {
    if (p->u_V < u_sat_V) below.insert(p->u_V);
  }
  if (below.size() < 4) return "fewer than 4 distinct openings below u_sat: a..d not identifiable";
  return {};
}

// The highest opening of `plateaus` (0 for none).
double TopOpening(const std::vector<const ValvePlateau*>& plateaus) {
  double top = 0;
  for (const auto* p : plateaus) top = std::max(top, p->u_V);
  return top;
}

KvpBand MakeBand(const double* theta, const double* covariance, double u_sat_V, double sigmas) {
  using Jet = ceres::Jet<double, kBranchParameters>;
  Jet jet_theta[kBranchParameters];
  for (int i = 0; i < kBranchParameters; ++i) jet_theta[i] = Jet(theta[i], i);
  const KvpCoefficients<Jet> c{jet_theta[1], jet_theta[2], jet_theta[3],
                               jet_theta[4], jet_theta[0], Jet(u_sat_V)};
  KvpBand band;
  for (int k = 0; k <= 100; ++k) {
    const double u = k / 100.0;
    const Jet value = Kvp(Jet(u), c);
    double variance = 0;
    for (int i = 0; i < kBranchParameters; ++i) {
      for (int j = 0; j < kBranchParameters; ++j) {
        variance += value.v[i] * covariance[i * kBranchParameters + j] * value.v[j];
      }
    }
    const double half_width = sigmas * std::sqrt(std::max(variance, 0.0));
    band.u_V.push_back(u);
    band.kvp.push_back(value.a);
    band.lower.push_back(value.a - half_width);
    band.upper.push_back(value.a + half_width);
  }
  return band;
}

// Every coefficient of the branch at `values`, with the standard errors of
// `covariance` (5 x 5 over q_max, a, b, c, d; nullptr: all held with `held`);
// u_sat held at its value as fixed.
void SetCoefficients(const std::string& prefix, const KvpBranchParams& start,
                     const KvpBranchParams& values, const double* covariance,
                     const std::string& held, BranchFit* fit) {
  const auto starts = Pack(start), fitted = Pack(values);
  fit->coefficients.clear();
  for (int i = 0; i < kBranchParameters; ++i) {
    FittedCoefficient c;
    c.path = prefix + "." + kParameterNames[i];
    c.start = starts[i];
    c.value = fitted[i];
    if (covariance != nullptr) {
      c.standard_error = std::sqrt(covariance[i * kBranchParameters + i]);
    } else {
      c.held = held;
    }
    fit->coefficients.push_back(c);
  }
  FittedCoefficient u_sat;
  u_sat.path = prefix + ".u_sat";
  u_sat.start = start.u_sat_V;
  u_sat.value = values.u_sat_V;
  u_sat.held = covariance == nullptr ? held : "fixed at the prior's (fit_u_sat is off)";
  fit->coefficients.push_back(u_sat);
  fit->covariance = Eigen::MatrixXd::Zero(kBranchParameters + 1, kBranchParameters + 1);
  if (covariance == nullptr) return;
  for (int i = 0; i < kBranchParameters; ++i) {
    for (int j = 0; j < kBranchParameters; ++j)
      fit->covariance(i, j) = covariance[i * kBranchParameters + j];
  }
}

}  // namespace

std::array<double, kBranchParameters> Pack(const KvpBranchParams& p) {
  return {p.q_max_kg_per_s, p.a, p.b, p.c, p.d};
}

// A reduced chi-square above this is said in the fit's note.
constexpr double kScatterNoted = 4.0;

BranchFit FitBranch(const std::vector<const ValvePlateau*>& plateaus, const KvpBranchParams& prior,
                    const std::string& prefix, const ValveFitOptions& options) {
  BranchFit fit;
  fit.params = prior;
  fit.plateaus = static_cast<int>(plateaus.size());
  const auto not_fitted = [&](const std::string& why) {
    fit.status = FitStatus::kNotFitted;
    fit.reason = why + "; the prior is kept";
    SetCoefficients(prefix, prior, prior, nullptr, why, &fit);
    return fit;
  };
  const std::string unidentifiable = Unidentifiable(plateaus, prior.u_sat_V);
  if (!unidentifiable.empty()) return not_fitted(unidentifiable);
  std::array<double, kBranchParameters> theta = Pack(prior);
  ceres::Problem problem;
  for (const ValvePlateau* p : plateaus) {
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<PlateauResidual, 1, kBranchParameters>(
            new PlateauResidual{p->u_V, p->kvp_kg_per_s, p->kvp_sigma, prior.u_sat_V}),
        nullptr, theta.data());
  }
  const double top_V = TopOpening(plateaus);
  const bool below_saturation = top_V < prior.u_sat_V;
  const bool q_max_held = below_saturation && top_V < kExtrapolationReach * prior.u_sat_V;
  if (q_max_held) {
    problem.SetManifold(theta.data(), new ceres::SubsetManifold(kBranchParameters, {0}));
  } else if (below_saturation) {
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<ContinuityResidual, 1, kBranchParameters>(
            new ContinuityResidual{prior.u_sat_V}),
        nullptr, theta.data());
  }
  ceres::Solver::Options solver_options = internal::QuietSolverOptions();
  solver_options.linear_solver_type = ceres::DENSE_QR;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.function_tolerance = 1e-12;
  solver_options.parameter_tolerance = 1e-12;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  fit.initial_cost = summary.initial_cost;
  fit.final_cost = summary.final_cost;
  fit.iterations = internal::StepsTried(summary);
  if (!summary.IsSolutionUsable()) return not_fitted("Ceres failed (" + summary.message + ")");
  ceres::Covariance::Options covariance_options;
  ceres::Covariance covariance(covariance_options);
  std::vector<std::pair<const double*, const double*>> blocks = {{theta.data(), theta.data()}};
  double c[kBranchParameters * kBranchParameters];
  if (!covariance.Compute(blocks, &problem) ||
      !covariance.GetCovarianceBlock(theta.data(), theta.data(), c)) {
    return not_fitted(
        "the coefficients are not identifiable from these plateaus (singular covariance)");
  }
  // Model error: plateaus that scatter about the quartic more than their
  // errors explain (a valve that is not quite a quartic, a lag not read)
  // widen its errors by the reduced chi-square when that is above 1.
  const double dof = static_cast<double>(summary.num_residuals - summary.num_effective_parameters);
  const double chi_square = dof > 0 ? 2 * summary.final_cost / dof : 1.0;
  if (chi_square > 1)
    for (double& v : c) v *= chi_square;
  char below[240] = "";
  if (q_max_held) {
    std::snprintf(below, sizeof(below),
                  "no plateau at or above u_sat %.3g V, the top opening %.3g V (below %.2g u_sat): "
                  "q_max held at the prior's, the polynomial fitted to K_vp below",
                  prior.u_sat_V, top_V, kExtrapolationReach);
  } else if (below_saturation) {
    std::snprintf(below, sizeof(below),
                  "no plateau at or above u_sat %.3g V, the top opening %.3g V: q_max is the "
                  "polynomial's value there, K_vp taken as continuous (+-%.2g %%)",
                  prior.u_sat_V, top_V, 100 * kContinuitySigma);
  }
  fit.status = summary.termination_type == ceres::NO_CONVERGENCE ? FitStatus::kNotConverged
                                                                 : FitStatus::kConverged;
  if (fit.status == FitStatus::kNotConverged) fit.reason = summary.message;
  if (below_saturation) fit.reason += (fit.reason.empty() ? "" : "; ") + std::string(below);
  if (chi_square > kScatterNoted) {
    char scatter[200];
    std::snprintf(scatter, sizeof(scatter),
                  "the plateaus scatter about the quartic %.3g times as much as their errors "
                  "explain (reduced chi-square): the errors are widened by its root",
                  chi_square);
    fit.reason += (fit.reason.empty() ? "" : "; ") + std::string(scatter);
  }
  fit.params = Unpack(theta.data(), prior.u_sat_V);
  SetCoefficients(prefix, prior, fit.params, c, "", &fit);
  if (q_max_held) fit.coefficients.front().held = below;
  fit.band = MakeBand(theta.data(), c, prior.u_sat_V, options.band_sigmas);
  return fit;
}

}  // namespace pneumaid::internal
