// Refinement (refine.h), its uncertainty: the information of the free
// parameters with the estimated starts eliminated, the covariance with model
// error and the fit's resolution, standard errors and correlations.
#pragma once

#include <Eigen/Core>
#include <functional>
#include <vector>

#include "pneumaid/ident/refine.h"
#include "refine_parameters.h"
#include "refine_residual.h"

namespace pneumaid::refine_internal {

// J^T J of the free parameters from one experiment's Jacobian, its start
// offsets (the last columns, when estimated) eliminated: the Schur complement
// A^T A - A^T B (B^T B)^-1 B^T A, so their uncertainty widens the parameters'.
Eigen::MatrixXd ParameterInformation(const EvaluationCache& at, int m);

// J^T r of the free parameters from one experiment, its start offsets
// eliminated (A^T r - A^T B (B^T B)^-1 B^T r): how hard the run pulls the
// parameters away from the common optimum. Runs that a mismatched model
// cannot all follow pull in different directions; the sum of the scores'
// outer products is the meat of the run-clustered covariance.
Eigen::VectorXd ParameterScore(const EvaluationCache& at, int m);

// The scores of one experiment's time blocks of `block_s` (every channel's
// rows of those samples; a short last block joins the one before, the start
// priors go with the first block), each with the start offsets eliminated as
// in ParameterScore; they sum to it. block_s <= 0: the one whole score.
std::vector<Eigen::VectorXd> BlockScores(const FitExperiment& e, const EvaluationCache& at, int m,
                                         double block_s);

// One clustering of the scores: the sum over its clusters of score score^T
// and their number.
struct ClusteredMeat {
  Eigen::MatrixXd meat;
  int clusters = 0;

  void Add(const Eigen::VectorXd& score) {
    if (meat.size() == 0) meat = Eigen::MatrixXd::Zero(score.size(), score.size());
    meat += score * score.transpose();
    ++clusters;
  }
};

// The lag-one autocorrelation of the weighted residuals, pooled over the
// channels of every run (a channel's first sample has no predecessor; the
// start priors are left out). White noise gives about 0; a model error that
// lasts many samples (mismatch, chaotic slips) gives nearly 1.
struct ResidualCorrelation {
  double lagged = 0, squared = 0;  // sum r_i r_(i+1), sum r_i^2

  // `weight`: the run's weight in the fit (a robust loss's slope; 1 else).
  void Add(const FitExperiment& e, const Eigen::VectorXd& residuals, double weight = 1.0);
  // internal::CorrelationInflation (determination.h): how much the
  // residuals' correlation widens the Gauss-Newton covariance.
  double Inflation() const;
};

// Covariance of the free parameters at the optimum, in their SI units, from
// the Gauss-Newton approximation (J^T J)^-1 (a pseudo-inverse: a direction
// the data do not determine gets no finite variance but no crash either),
// inflated by the reduced chi-square when the model misses the data by more
// than the declared noise (the honest reading of a misfit) and by the
// residuals' correlation (`correlation_inflation`, ResidualCorrelation: a
// misfit that lasts many samples is not many independent errors), plus the fit's
// numerical resolution: the cost of the event-driven model jitters at
// `cost_resolution` (relative), so every point whose cost lies within
// cost_resolution x cost of the minimum is as good a stop as any; along
// parameter j that band reaches sqrt(2 cost_resolution cost (J^T J)^-1_jj).
// Without that term the errors were 5 to 20 times smaller than the distance
// to the truth on synthetic units. `normal` is J^T J of the free parameters
// with any estimated starts eliminated.
// Robust over runs and time: for each clustering of the scores (the runs,
// ParameterScore; the time blocks, BlockScores) with G >= 2 clusters, each
// parameter's variance is widened to that clustered sandwich's,
// N^-1 meat N^-1 G/(G-1), where that is larger (the correlations kept):
// where the runs, or the stretches of one run, disagree about a parameter
// more than their noise and misfit say (model error that differs from run
// to run or from slide to slide) its error widens. Empty on failure.
Eigen::MatrixXd ParameterCovariance(const Eigen::MatrixXd& normal, const ParameterMap& map,
                                    const std::vector<double>& theta, double cost, long residuals,
                                    double correlation_inflation, double cost_resolution,
                                    const std::vector<ClusteredMeat>& clusterings = {});

// How rough the cost is at the scale of the parameters' uncertainty: the
// root mean square, over a stencil of `directions` pairs theta +- d (d one
// standard deviation of `theta_cov` long, Mahalanobis length 1, toward a
// fixed pseudo-random corner of the unit cube), of how far the pair's mean
// rise falls short of the rise the Gauss-Newton curvature predicts,
// 0.5 d^T `normal` d (`normal`: the runs' J^T J with the starts held). The
// pair's mean cancels a slope (a stall, the pull of a prior); a smooth cost
// gives about 0, and so does one that rises faster than predicted (the
// curvature then overstates the uncertainty: nothing to widen); an
// event-driven cost whose stick/slip switches move across the stencil gives
// the size of its drops, and a cost that flattens out within one standard
// error (the curvature overstates the information) the size of the
// shortfall. `cost` evaluates the cost at theta (NaN: failed, the pair is
// skipped); `cost_at_theta` is its value at the optimum. 0 without a usable
// pair.
double StencilJitter(const std::function<double(const std::vector<double>&)>& cost,
                     const std::vector<double>& theta, double cost_at_theta,
                     const Eigen::MatrixXd& theta_cov, const Eigen::MatrixXd& normal,
                     int directions);

// Standard errors into r's parameters and uncertainty, correlations and the
// poorly separable pairs. A coefficient at a bound gets none (its row and
// column of the covariance zeroed, no uncertainty entry): the mapped
// coordinate's slope vanishes there and its uncertainty is one-sided.
void Summarise(const Eigen::MatrixXd& cov, const ParameterMap& map, const RefineOptions& options,
               RefineResult* r);

// Where the refined value of a coefficient and the start's (with its
// standard error in start.uncertainty: a component fit, an experiment of its
// own for the valve and the tube) disagree by more than their errors allow,
// chi2 = (value - start)^2 / (se^2 + se_start^2) > 1, the refined error is
// widened. Against an experiment of its own (valve.* from the staircase,
// pipeline.* from the tube tests: any coefficient but friction) the excess
// of the squared difference over both variances, tau^2 = d^2 - se^2 -
// se_start^2, is a between-method variance (DerSimonian and Laird's random
// effects) added to the refined one: se' = sqrt(d^2 - se_start^2). Against
// the friction replay, which reads the same stroke logs through another
// model, the refined error grows to the distance, se' = |d| (the replay's
// value within one error). Until session 20 this was the Particle Data
// Group's scale factor sqrt(chi2); with the replay's errors widened by the
// logs' readings (friction_covariance.h) it widened too little (refined
// coefficients within 3 errors 89 % and 88 % on the sweep's seeds 12 and 57;
// with se' = |d| 92 % and 90 %, within 1 68 % on both). A model error
// common to all runs is invisible to the misfit's
// scale and to the run clusters, but not to another experiment. The
// covariance's row and column scale with it (correlations kept).
// Coefficients at a bound, held, or without a start error are left as they
// are.
void WidenByStartDisagreement(const Parameters& start, RefineResult* r);

}  // namespace pneumaid::refine_internal
