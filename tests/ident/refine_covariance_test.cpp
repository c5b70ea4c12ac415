// Refinement's uncertainty (src/ident/refine_covariance.h): the residuals'
// lag-one autocorrelation that widens the covariance when a misfit lasts
// many samples, the run-clustered sandwich that widens it where the runs
// disagree, the time-block-clustered one, no error at a bound, the stencil
// that measures the cost's roughness. Closed forms on seeded synthetic residuals.
#include "../../src/ident/refine_covariance.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

namespace pneumaid::refine_internal {
namespace {

constexpr int kSamples = 20000;

// A run of `samples` samples with the x and p1 channels.
FitExperiment TwoChannelRun(int samples = kSamples) {
  FitExperiment e;
  e.measured.t_s.resize(samples);
  for (int i = 0; i < samples; ++i) e.measured.t_s[i] = 1e-3 * i;
  e.channels = {kChannelTable[0], kChannelTable[1]};
  return e;
}

// Each channel an AR(1) series r_i = rho r_(i-1) + e_i (seeded).
Eigen::VectorXd Ar1(double rho, std::uint64_t seed) {
  std::mt19937_64 random(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  Eigen::VectorXd r(2 * kSamples);
  for (int c = 0; c < 2; ++c) {
    double previous = noise(random) / std::sqrt(1 - rho * rho);
    for (int i = 0; i < kSamples; ++i) {
      previous = rho * previous + noise(random);
      r[c * kSamples + i] = previous;
    }
  }
  return r;
}

TEST(ResidualCorrelationTest, WhiteResidualsDoNotWidenTheCovariance) {
  ResidualCorrelation correlation;
  correlation.Add(TwoChannelRun(), Ar1(0.0, 1));
  EXPECT_NEAR(correlation.Inflation(), 1.0, 0.03);
}

TEST(ResidualCorrelationTest, AnAr1MisfitWidensItByOnePlusRhoOverOneMinusRho) {
  ResidualCorrelation correlation;
  correlation.Add(TwoChannelRun(), Ar1(0.9, 2));
  EXPECT_NEAR(correlation.Inflation(), 19.0, 0.1 * 19.0);
}

TEST(ResidualCorrelationTest, PoolsRunsAndNeverNarrowsIt) {
  ResidualCorrelation correlation;
  Eigen::VectorXd alternating(2 * kSamples);
  for (int i = 0; i < 2 * kSamples; ++i) alternating[i] = i % 2 ? 1.0 : -1.0;
  correlation.Add(TwoChannelRun(), alternating);
  EXPECT_DOUBLE_EQ(correlation.Inflation(), 1.0);  // rho = -1: no narrowing
  // The pooled rho weighs each run by its squared residuals: an AR(1) run
  // of ten times the innovation (variance 100 / (1 - 0.81) per sample)
  // dominates the alternating one (variance 1, lag product -1).
  correlation.Add(TwoChannelRun(), 10.0 * Ar1(0.9, 3));
  const double variance = 100.0 / (1 - 0.81);
  const double rho = (0.9 * variance - 1) / (variance + 1);
  EXPECT_NEAR(correlation.Inflation(), (1 + rho) / (1 - rho), 0.1 * (1 + rho) / (1 - rho));
}

// A run the robust loss down-weights counts with its weight: at weight 0
// an AR(1) run leaves the white one's factor.
TEST(ResidualCorrelationTest, ARunCountsWithItsWeight) {
  ResidualCorrelation correlation;
  correlation.Add(TwoChannelRun(), Ar1(0.0, 4));
  correlation.Add(TwoChannelRun(), 10.0 * Ar1(0.95, 5), 0.0);
  EXPECT_NEAR(correlation.Inflation(), 1.0, 0.03);
  correlation.Add(TwoChannelRun(), 10.0 * Ar1(0.95, 5), 1.0);
  EXPECT_GT(correlation.Inflation(), 20.0);
}

// Where the channels meet, the last sample of one and the first of the next
// are not neighbours: channels (1, 1) and (-1, -1) give rho = 2 / 4 (the
// seam's product -1 would make it 1 / 4).
TEST(ResidualCorrelationTest, ChannelsAreNotNeighbours) {
  ResidualCorrelation correlation;
  Eigen::VectorXd steps(4);
  steps << 1.0, 1.0, -1.0, -1.0;
  correlation.Add(TwoChannelRun(2), steps);
  EXPECT_DOUBLE_EQ(correlation.Inflation(), (1 + 0.5) / (1 - 0.5));
}

// Two free parameters, linear scale over [-10, 10], at theta = 0 (the middle:
// dp/dtheta = 20 / 4 = 5).
ParameterMap TwoLinearParameters() {
  ParameterMap map;
  for (const char* path : {"a", "b"}) {
    FreeParameter p;
    p.path = path;
    p.lower = -10;
    p.upper = 10;
    p.scale = ParameterScale::kLinear;
    map.free.push_back(p);
  }
  return map;
}

TEST(RunClusteredErrorsTest, TheScoreHasTheStartOffsetsEliminated) {
  // Columns: two parameters, then one start offset.
  EvaluationCache at;
  at.jacobian.resize(4, 3);
  at.jacobian << 1, 0, 1, 0, 1, 1, 1, 1, 0, 2, 0, 1;
  at.residuals.resize(4);
  at.residuals << 0.5, -1, 2, 0.25;
  const Eigen::MatrixXd a = at.jacobian.leftCols(2), b = at.jacobian.rightCols(1);
  const Eigen::VectorXd expected =
      a.transpose() * at.residuals -
      a.transpose() * b * (b.transpose() * b).inverse() * b.transpose() * at.residuals;
  const Eigen::VectorXd score = ParameterScore(at, 2);
  ASSERT_EQ(score.size(), 2);
  EXPECT_NEAR(score[0], expected[0], 1e-12);
  EXPECT_NEAR(score[1], expected[1], 1e-12);
  // Without offsets it is J^T r.
  EvaluationCache plain;
  plain.jacobian = at.jacobian.leftCols(2);
  plain.residuals = at.residuals;
  EXPECT_NEAR(ParameterScore(plain, 2)[0], (a.transpose() * at.residuals)[0], 1e-12);
}

// Runs that pull the parameters apart widen each error to the sandwich's,
// N^-1 (sum of the scores' outer products) N^-1 G / (G - 1), where that is
// larger (in values, correlations kept); scores as the noise alone gives
// them do not widen anything.
// Two linear parameters at theta = 0 with J^T J = [4 1; 1 2] and a cost at
// the noise (reduced chi-square 1), white residuals, no resolution term: the
// plain covariance is N^-1 in theta, 25 N^-1 in values.
struct TwoParameterFit {
  const ParameterMap map = TwoLinearParameters();
  const std::vector<double> theta = {0.0, 0.0};
  const Eigen::MatrixXd normal = (Eigen::MatrixXd(2, 2) << 4, 1, 1, 2).finished();
  const Eigen::MatrixXd inverse = normal.inverse();
  const long rows = 1002;
  const double cost = 0.5 * (rows - 2);

  Eigen::MatrixXd Covariance(const std::vector<ClusteredMeat>& clusterings = {}) const {
    return ParameterCovariance(normal, map, theta, cost, rows, 1.0, 0.0, clusterings);
  }
};

TEST(RunClusteredErrorsTest, RunsThatDisagreeWidenTheErrorsToTheSandwich) {
  const TwoParameterFit fit;
  const Eigen::MatrixXd& inverse = fit.inverse;
  const Eigen::MatrixXd plain = fit.Covariance();
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(plain(i, i), 25.0 * inverse(i, i), 1e-9);
  // Two runs pulling the first parameter apart, far beyond the noise.
  Eigen::Vector2d g1(6, 0), g2(-6, 0);
  const Eigen::MatrixXd meat = g1 * g1.transpose() + g2 * g2.transpose();
  const Eigen::MatrixXd robust = fit.Covariance({{meat, 2}});
  const Eigen::MatrixXd sandwich = 25.0 * inverse * meat * inverse * 2.0;
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(robust(i, i), std::max(plain(i, i), sandwich(i, i)), 1e-9) << i;
  }
  EXPECT_GT(robust(0, 0), 2 * plain(0, 0));
  // The correlation is the plain one.
  EXPECT_NEAR(robust(0, 1) / std::sqrt(robust(0, 0) * robust(1, 1)),
              plain(0, 1) / std::sqrt(plain(0, 0) * plain(1, 1)), 1e-12);
  // Scores as the noise gives them: G clusters whose scores sum to zero carry
  // (G - 1) / G N in expectation, the sandwich is then N^-1: nothing widens.
  const Eigen::MatrixXd noise = fit.Covariance({{0.5 * fit.normal, 2}});
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 2; ++j) EXPECT_NEAR(noise(i, j), plain(i, j), 1e-9);
  // One run alone is no cluster.
  const Eigen::MatrixXd single = fit.Covariance({{meat, 1}});
  EXPECT_NEAR(single(0, 0), plain(0, 0), 1e-12);
}

// A coefficient on a bound gets no standard error (the mapped slope vanishes
// there, and the uncertainty is one-sided); the others keep theirs.
TEST(RunClusteredErrorsTest, ACoefficientAtABoundHasNoStandardError) {
  const ParameterMap map = TwoLinearParameters();
  RefineResult r;
  r.coefficients.resize(2);
  r.coefficients[0].path = "a";
  r.coefficients[1].path = "b";
  r.coefficients[1].at_bound = true;
  r.params.uncertainty["b"] = 1.0;
  Eigen::MatrixXd cov(2, 2);
  cov << 4, 0, 0, 1e-200;
  Summarise(cov, map, RefineOptions{}, &r);
  EXPECT_DOUBLE_EQ(r.coefficients[0].standard_error, 2.0);
  EXPECT_EQ(r.params.uncertainty.at("a"), 2.0);
  EXPECT_EQ(r.coefficients[1].standard_error, 0.0);
  EXPECT_EQ(r.params.uncertainty.count("b"), 0u);
  EXPECT_EQ(r.covariance(1, 1), 0.0);
  EXPECT_EQ(r.covariance(0, 1), 0.0);
  EXPECT_NE(r.CoefficientReport().find("at a bound: no standard error"), std::string::npos);
}

// Two experiments that disagree: the refined value 10 +- 0.1 against the
// component fit's 9 +- 0.2 is chi2 = 1 / 0.05 = 20 > 1, so the refined error
// grows to the distance, 1 (a factor 10), its covariance row and column with
// it. A coefficient within its errors of the start, one at a bound and one
// the start carries no error for are left as they are.
// Friction against the replay of the same logs (the distance);
// pipeline.delta against the tube tests, an experiment of its own (the
// between-method variance).
TEST(StartDisagreementTest, DisagreeingExperimentsWidenTheRefinedError) {
  RefineResult r;
  Parameters start;
  const char* paths[] = {"friction.positive.Fs", "friction.positive.Fd", "friction.positive.b",
                         "friction.positive.vs", "pipeline.delta"};
  const double values[] = {10.0, 5.05, 3.0, 2.0, 10.0}, starts[] = {9.0, 5.0, 1.0, 1.0, 9.0};
  for (int i = 0; i < 5; ++i) {
    FittedCoefficient c;
    c.path = paths[i];
    c.value = values[i];
    c.start = starts[i];
    c.standard_error = 0.1;
    r.coefficients.push_back(c);
    r.params.uncertainty[paths[i]] = 0.1;
  }
  r.coefficients[2].at_bound = true;
  start.uncertainty = {{paths[0], 0.2}, {paths[1], 0.2}, {paths[2], 0.2}, {paths[4], 0.2}};
  r.covariance = Eigen::MatrixXd::Constant(5, 5, 0.005);
  r.covariance.diagonal().setConstant(0.01);
  WidenByStartDisagreement(start, &r);
  // chi2 = 1 / (0.01 + 0.04) = 20 > 1: the error grows to the distance, 1.
  EXPECT_NEAR(r.coefficients[0].standard_error, 1.0, 1e-12);
  EXPECT_NEAR(r.params.uncertainty.at(paths[0]), 1.0, 1e-12);
  EXPECT_NEAR(r.covariance(0, 0), 1.0, 1e-12);
  EXPECT_NEAR(r.covariance(0, 1), 0.005 * 10.0, 1e-12);
  EXPECT_NEAR(r.covariance(1, 0), 0.005 * 10.0, 1e-12);
  // tau^2 = 1 - 0.01 - 0.04 added to 0.01: se' = sqrt(1 - 0.04), more than
  // the PDG scale factor sqrt(chi2) would give; the start's value lies
  // within 1.1 se'.
  const double widened = std::sqrt(0.96);
  EXPECT_NEAR(r.coefficients[4].standard_error, widened, 1e-12);
  EXPECT_NEAR(r.params.uncertainty.at("pipeline.delta"), widened, 1e-12);
  EXPECT_NEAR(r.covariance(4, 4), widened * widened, 1e-12);
  EXPECT_NEAR(r.covariance(4, 1), 0.005 * widened / 0.1, 1e-12);
  EXPECT_NEAR(r.covariance(0, 4), 0.005 * 10.0 * widened / 0.1, 1e-12);
  EXPECT_GT(widened, 0.1 * std::sqrt(20.0));
  for (int i = 1; i < 4; ++i) {
    EXPECT_EQ(r.coefficients[i].standard_error, 0.1) << paths[i];
    EXPECT_EQ(r.covariance(i, i), 0.01) << paths[i];
  }
  EXPECT_EQ(r.covariance(1, 2), 0.005);
}

// The time blocks' scores sum to the run's score (start offsets eliminated,
// the start priors' rows with the first block); a short last block joins
// the one before.
TEST(BlockClusteredErrorsTest, TheBlocksScoresSumToTheRunsScore) {
  const int samples = 10;  // 1 ms apart
  const FitExperiment e = TwoChannelRun(samples);
  std::mt19937_64 random(7);
  std::normal_distribution<double> draw(0.0, 1.0);
  EvaluationCache at;
  // Two channels of 10 rows, then two prior rows; two parameters, one offset.
  at.jacobian.resize(2 * samples + 2, 3);
  at.residuals.resize(2 * samples + 2);
  for (int i = 0; i < at.jacobian.rows(); ++i) {
    for (int j = 0; j < 3; ++j) at.jacobian(i, j) = draw(random);
    at.residuals[i] = draw(random);
  }
  const std::vector<Eigen::VectorXd> blocks = BlockScores(e, at, 2, 3e-3);
  ASSERT_EQ(blocks.size(), 3u);  // samples 0-2, 3-5, 6-9
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(2);
  for (const auto& b : blocks) sum += b;
  const Eigen::VectorXd whole = ParameterScore(at, 2);
  EXPECT_NEAR(sum[0], whole[0], 1e-12);
  EXPECT_NEAR(sum[1], whole[1], 1e-12);
  // Without offsets, a middle block is A^T r over its samples of both channels.
  EvaluationCache plain;
  plain.jacobian = at.jacobian.leftCols(2);
  plain.residuals = at.residuals;
  const Eigen::VectorXd middle = BlockScores(e, plain, 2, 3e-3)[1];
  Eigen::VectorXd expected = Eigen::VectorXd::Zero(2);
  for (int c = 0; c < 2; ++c) {
    for (int i = 3; i < 6; ++i) {
      const int row = c * samples + i;
      expected += plain.jacobian.row(row).transpose() * plain.residuals[row];
    }
  }
  EXPECT_NEAR(middle[0], expected[0], 1e-12);
  EXPECT_NEAR(middle[1], expected[1], 1e-12);
  // No block length: the one score.
  EXPECT_EQ(BlockScores(e, at, 2, 0.0).size(), 1u);
}

// With two clusterings (the runs and the time blocks), each error widens to
// the larger of the two sandwiches.
TEST(BlockClusteredErrorsTest, EachErrorWidensToTheLargestSandwich) {
  const TwoParameterFit fit;
  const Eigen::MatrixXd& inverse = fit.inverse;
  const Eigen::MatrixXd plain = fit.Covariance();
  // The runs disagree about a, the blocks about b.
  ClusteredMeat runs, blocks;
  runs.Add(Eigen::Vector2d(6, 0));
  runs.Add(Eigen::Vector2d(-6, 0));
  for (int k = 0; k < 4; ++k) blocks.Add(Eigen::Vector2d(0, k % 2 ? 5.0 : -5.0));
  EXPECT_EQ(blocks.clusters, 4);
  const Eigen::MatrixXd both = fit.Covariance({runs, blocks});
  const Eigen::MatrixXd by_runs = 25.0 * inverse * runs.meat * inverse * 2.0;
  const Eigen::MatrixXd by_blocks = 25.0 * inverse * blocks.meat * inverse * (4.0 / 3.0);
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(both(i, i), std::max({plain(i, i), by_runs(i, i), by_blocks(i, i)}), 1e-9) << i;
  }
}

// The stencil measures how far the cost falls short of its curvature's
// prediction one standard deviation out: nothing for a quadratic cost, one
// that rises faster or a slope, the shortfall of a flatter cost (which pins
// the stencil's length), the drop for a cost whose optimum is a spike.
TEST(CostResolutionTest, TheStencilMeasuresTheCostsShortfall) {
  Eigen::MatrixXd normal(2, 2);
  normal << 4, 1, 1, 2;
  const Eigen::MatrixXd cov = 3.0 * normal.inverse();
  const std::vector<double> theta = {1.0, -2.0};
  const auto quadratic = [&](const std::vector<double>& at) {
    const Eigen::Vector2d d(at[0] - theta[0], at[1] - theta[1]);
    return 100.0 + 0.5 * d.dot(normal * d);
  };
  EXPECT_NEAR(StencilJitter(quadratic, theta, 100.0, cov, normal, 3), 0.0, 1e-12);
  const auto steeper = [&](const std::vector<double>& at) { return 2 * quadratic(at) - 100.0; };
  EXPECT_NEAR(StencilJitter(steeper, theta, 100.0, cov, normal, 3), 0.0, 1e-12);
  // Half the curvature: one standard deviation of cov = 3 N^-1 (Mahalanobis
  // length 1) has d^T N d = 3, predicted 1.5, rises 0.75: short by 0.75.
  const auto flatter = [&](const std::vector<double>& at) { return 0.5 * quadratic(at) + 50.0; };
  EXPECT_NEAR(StencilJitter(flatter, theta, 100.0, cov, normal, 3), 0.75, 1e-12);
  // A slope (a stall, a prior's pull) cancels in each pair's mean.
  const auto sloped = [&](const std::vector<double>& at) {
    return quadratic(at) + 40.0 * (at[0] - theta[0]) - 25.0 * (at[1] - theta[1]);
  };
  EXPECT_NEAR(StencilJitter(sloped, theta, 100.0, cov, normal, 3), 0.0, 1e-9);
  // Every point off the optimum 0.7 lower than the quadratic: a drop of 0.7.
  const auto spike = [&](const std::vector<double>& at) { return quadratic(at) - 0.7; };
  EXPECT_NEAR(StencilJitter(spike, theta, 100.0, cov, normal, 3), 0.7, 1e-12);
  // Failed points are skipped; with none usable, 0.
  const auto failing = [](const std::vector<double>&) { return NAN; };
  EXPECT_EQ(StencilJitter(failing, theta, 100.0, cov, normal, 3), 0.0);
  EXPECT_EQ(StencilJitter(spike, theta, 100.0, cov, normal, 0), 0.0);
}

}  // namespace
}  // namespace pneumaid::refine_internal
