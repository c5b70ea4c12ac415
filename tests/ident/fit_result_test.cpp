// The one result type of every fit: combining parts, correlations, applying
// values to a parameter set, and the report's held lines.
#include "pneumaid/ident/fit_result.h"

#include <gtest/gtest.h>

#include <cmath>

namespace pneumaid {
namespace {

FitResult OneCoefficient(const std::string& path, double value, double error, FitStatus status) {
  FitResult fit;
  fit.status = status;
  fit.coefficients.push_back({path, 1.0, value, error, "", false});
  fit.covariance = Eigen::MatrixXd::Constant(1, 1, error * error);
  fit.iterations = 3;
  fit.final_cost = 2.0;
  return fit;
}

TEST(FitResultTest, AppendCombinesCoefficientsCovarianceAndStatus) {
  FitResult whole;
  AppendFit(OneCoefficient("friction.positive.Fs", 9.0, 0.5, FitStatus::kConverged), "positive",
            &whole);
  EXPECT_EQ(whole.status, FitStatus::kConverged);
  FitResult failed = OneCoefficient("friction.negative.Fs", 10.0, 0.0, FitStatus::kNotFitted);
  failed.reason = "no slide";
  failed.coefficients[0].held = "no slide";
  AppendFit(failed, "negative", &whole);
  // A part that fitted nothing does not make the whole "not fitted".
  EXPECT_EQ(whole.status, FitStatus::kConverged);
  EXPECT_EQ(whole.reason, "negative: no slide");
  ASSERT_EQ(whole.coefficients.size(), 2u);
  ASSERT_EQ(whole.covariance.rows(), 2);
  EXPECT_DOUBLE_EQ(whole.covariance(0, 0), 0.25);
  EXPECT_DOUBLE_EQ(whole.covariance(0, 1), 0.0);  // independent fits: block diagonal
  EXPECT_EQ(whole.iterations, 6);
  EXPECT_DOUBLE_EQ(whole.final_cost, 4.0);
  // The worst status of the parts that fitted wins.
  AppendFit(OneCoefficient("pipeline.delta", 8.0, 0.1, FitStatus::kNotConverged), "tube", &whole);
  EXPECT_EQ(whole.status, FitStatus::kNotConverged);
  // Only parts that fitted nothing: not fitted.
  FitResult nothing;
  AppendFit(failed, "a", &nothing);
  AppendFit(failed, "b", &nothing);
  EXPECT_EQ(nothing.status, FitStatus::kNotFitted);
  EXPECT_FALSE(nothing.has_values());
}

TEST(FitResultTest, CorrelatedPairsSkipHeldCoefficients) {
  FitResult fit;
  fit.status = FitStatus::kConverged;
  fit.coefficients = {{"valve.increasing.a", 0, 1, 1, "", false},
                      {"valve.increasing.b", 0, 1, 1, "", false},
                      {"valve.increasing.c", 0, 1, 1, "not determined", false}};
  fit.covariance.resize(3, 3);
  fit.covariance << 1.0, -0.99, 0.99, -0.99, 1.0, -0.99, 0.99, -0.99, 1.0;
  EXPECT_NEAR(fit.Correlation(0, 1), -0.99, 1e-12);
  EXPECT_TRUE(std::isnan(fit.Correlation(0, 7)));
  const auto pairs = fit.Correlated(0.95);
  ASSERT_EQ(pairs.size(), 1u);
  EXPECT_EQ(pairs[0], std::make_pair(std::size_t{0}, std::size_t{1}));
  const std::string report = fit.CoefficientReport();
  EXPECT_NE(report.find("valve.increasing.c"), std::string::npos);
  EXPECT_NE(report.find("held: not determined"), std::string::npos);
  EXPECT_NE(report.find("poorly separable: valve.increasing.a, valve.increasing.b"),
            std::string::npos);
}

TEST(FitResultTest, ApplyWritesEveryValueOnlyWhenThereAreValues) {
  FitResult fit = OneCoefficient("friction.negative.b", 12.5, 0.2, FitStatus::kConverged);
  Parameters params;
  fit.ApplyTo(&params);
  EXPECT_EQ(params.friction.negative.viscous_N_s_per_m, 12.5);
  fit.status = FitStatus::kNotFitted;
  fit.coefficients[0].value = 99.0;
  fit.ApplyTo(&params);
  EXPECT_EQ(params.friction.negative.viscous_N_s_per_m, 12.5);
  EXPECT_EQ(fit.Find("friction.negative.b")->value, 99.0);
  EXPECT_EQ(fit.Find("friction.negative.Fs"), nullptr);
}

TEST(FitResultTest, StatusesReadAsTheReportsSayThem) {
  EXPECT_STREQ(ToString(FitStatus::kConverged), "converged");
  EXPECT_STREQ(ToString(FitStatus::kNotExplained), "the model does not explain these logs");
  EXPECT_STREQ(ToString(FitStatus::kNotFitted), "not fitted");
  const FitError error("the identified set of unit U", "not physical: friction.positive.Fs");
  EXPECT_EQ(error.object(), "the identified set of unit U");
  EXPECT_STREQ(error.what(), "the identified set of unit U: not physical: friction.positive.Fs");
}

// One rule for "at a bound", for every fit: within 1e-6 of the span from
// either end, exact bounds included, the interior not.
TEST(FitResultTest, AtABoundIsWithinAMillionthOfTheSpan) {
  EXPECT_TRUE(AtBound(0.0, 0.0, 200.0));
  EXPECT_TRUE(AtBound(200.0, 0.0, 200.0));
  EXPECT_TRUE(AtBound(1e-4 + 1e-7, 1e-4, 1.0));
  EXPECT_TRUE(AtBound(200.0 - 1e-4, 0.0, 200.0));
  EXPECT_FALSE(AtBound(1e-3, 0.0, 200.0));
  EXPECT_FALSE(AtBound(100.0, 0.0, 200.0));
}

}  // namespace

}  // namespace pneumaid
