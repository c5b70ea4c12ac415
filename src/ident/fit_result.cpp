#include "pneumaid/ident/fit_result.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "pneumaid/model/parameter_table.h"

namespace pneumaid {

bool AtBound(double value, double lower, double upper) {
  return std::min(value - lower, upper - value) < 1e-6 * (upper - lower);
}

const char* ToString(FitStatus status) {
  switch (status) {
    case FitStatus::kConverged:
      return "converged";
    case FitStatus::kNotExplained:
      return "the model does not explain these logs";
    case FitStatus::kNotConverged:
      return "NOT converged";
    case FitStatus::kNotFitted:
      return "not fitted";
  }
  return "?";
}

const FittedCoefficient* FitResult::Find(const std::string& path) const {
  for (const FittedCoefficient& c : coefficients) {
    if (c.path == path) return &c;
  }
  return nullptr;
}

std::map<std::string, std::string> FitResult::Held() const {
  std::map<std::string, std::string> held;
  for (const FittedCoefficient& c : coefficients) {
    if (has_values() && c.determined()) continue;
    held[c.path] = !c.held.empty() ? c.held : !reason.empty() ? reason : ToString(status);
  }
  return held;
}

double FitResult::Correlation(std::size_t i, std::size_t j) const {
  const auto n = static_cast<std::size_t>(covariance.rows());
  if (i >= n || j >= n) return NAN;
  const double scale = std::sqrt(covariance(i, i) * covariance(j, j));
  return scale > 0 ? covariance(i, j) / scale : NAN;
}

std::vector<std::pair<std::size_t, std::size_t>> FitResult::Correlated(double threshold) const {
  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  for (std::size_t i = 0; i < coefficients.size(); ++i) {
    for (std::size_t j = i + 1; j < coefficients.size(); ++j) {
      if (!coefficients[i].determined() || !coefficients[j].determined()) continue;
      const double r = Correlation(i, j);
      if (std::fabs(r) > threshold) pairs.emplace_back(i, j);
    }
  }
  return pairs;
}

void FitResult::ApplyTo(Parameters* params) const {
  if (!has_values()) return;
  for (const FittedCoefficient& c : coefficients) SetParameter(params, c.path, c.value);
}

std::string FitResult::CoefficientReport(const std::string& indent, double correlation_flag) const {
  std::ostringstream out;
  char line[512];
  for (const FittedCoefficient& c : coefficients) {
    if (c.determined() && c.at_bound && c.standard_error == 0) {
      std::snprintf(line, sizeof(line),
                    "%s%-28s %12.6g -> %12.6g  (at a bound: no standard error)\n", indent.c_str(),
                    c.path.c_str(), c.start, c.value);
    } else if (c.determined()) {
      std::snprintf(line, sizeof(line), "%s%-28s %12.6g -> %12.6g +- %.3g%s\n", indent.c_str(),
                    c.path.c_str(), c.start, c.value, c.standard_error,
                    c.at_bound ? "  (at a bound)" : "");
    } else {
      std::snprintf(line, sizeof(line), "%s%-28s %12.6g -> %12.6g  held: %s\n", indent.c_str(),
                    c.path.c_str(), c.start, c.value, c.held.c_str());
    }
    out << line;
  }
  for (const auto& [i, j] : Correlated(correlation_flag)) {
    std::snprintf(line, sizeof(line), "%spoorly separable: %s, %s correlation %.4f\n",
                  indent.c_str(), coefficients[i].path.c_str(), coefficients[j].path.c_str(),
                  Correlation(i, j));
    out << line;
  }
  return out.str();
}

void AppendFit(const FitResult& part, const std::string& name, FitResult* whole) {
  const auto n = static_cast<Eigen::Index>(whole->coefficients.size());
  const auto m = static_cast<Eigen::Index>(part.coefficients.size());
  Eigen::MatrixXd covariance = Eigen::MatrixXd::Zero(n + m, n + m);
  if (whole->covariance.rows() == n) covariance.topLeftCorner(n, n) = whole->covariance;
  if (part.covariance.rows() == m) covariance.bottomRightCorner(m, m) = part.covariance;
  whole->covariance = covariance;
  whole->coefficients.insert(whole->coefficients.end(), part.coefficients.begin(),
                             part.coefficients.end());
  whole->initial_cost += part.initial_cost;
  whole->final_cost += part.final_cost;
  whole->iterations += part.iterations;
  if (!part.reason.empty()) {
    whole->reason += (whole->reason.empty() ? "" : "; ") + name + ": " + part.reason;
  }
  // Not fitted only when every part is; otherwise the worst status of the
  // parts that fitted (the enum runs from best to worst).
  if (part.status == FitStatus::kNotFitted) return;
  whole->status =
      whole->status == FitStatus::kNotFitted ? part.status : std::max(whole->status, part.status);
}

FitError::FitError(std::string object, std::string message)
    : std::runtime_error(object + ": " + message),
      object_(std::move(object)),
      message_(std::move(message)) {}

}  // namespace pneumaid
