#include "refine_verdict.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "refine_parameters.h"
#include "refine_residual.h"
#include "windowed_measures.h"

namespace pneumaid::refine_internal {

std::vector<ChannelMisfit> RunMisfits(const FitExperiment& e, const Eigen::VectorXd& residuals,
                                      double window_s) {
  std::vector<ChannelMisfit> out;
  const Eigen::Index n = static_cast<Eigen::Index>(e.measured.size());
  const std::vector<double>& t = e.measured.t_s;
  const std::string run = e.parent.empty() ? e.id : e.parent;
  for (std::size_t c = 0; c < e.channels.size(); ++c) {
    const auto r = residuals.segment(static_cast<Eigen::Index>(c) * n, n);
    ChannelMisfit m;
    m.run = run;
    m.channel = e.channels[c].name;
    m.reduced_chi_square = n > 0 ? r.squaredNorm() / static_cast<double>(n) : 0.0;
    m.samples = static_cast<int>(n);
    // The worst window: a running sum over window_s.
    double sum = 0;
    Eigen::Index from = 0;
    for (Eigen::Index i = 0; i < n; ++i) {
      sum += r[i] * r[i];
      while (t[i] - t[from] > window_s) sum -= r[from] * r[from], ++from;
      const double mean = sum / static_cast<double>(i - from + 1);
      if (t[i] - t[from] >= 0.5 * window_s && mean > m.worst_reduced_chi_square) {
        m.worst_reduced_chi_square = mean;
        m.worst_from_s = t[from];
        m.worst_to_s = t[i];
      }
    }
    out.push_back(m);
  }
  return out;
}

std::vector<ChannelMisfit> MisfitsOf(const std::vector<RunResiduals>& runs, double window_s) {
  std::vector<ChannelMisfit> out;
  for (const RunResiduals& run : runs) {
    for (const ChannelMisfit& m : RunMisfits(run.run, run.residuals, window_s)) out.push_back(m);
  }
  return out;
}

std::vector<ChannelMisfit> WholeRunMisfits(const Parameters& params, const Unit& unit,
                                           const FitSpec& spec, const RefineOptions& options) {
  return MisfitsOf(WholeRunResiduals(params, unit, spec, options), options.misfit_window_s);
}

double VerdictMeasure(const Parameters& params, const Unit& unit, const FitSpec& spec,
                      const RefineOptions& options) {
  const double chi = MedianRunChiSquare(WholeRunMisfits(params, unit, spec, options));
  return std::isnan(chi) ? HUGE_VAL : chi;
}

double WindowedMeasure(const Parameters& params, const Unit& unit, const FitSpec& spec,
                       const RefineOptions& options, double above, bool* exact) {
  return WindowedMeasures(unit, spec, options).Measure(params, above, exact);
}

namespace {

// What a misfit weighs when chi-squares are pooled: its rows, at least 1
// (the one home of that rule: runs' channels, a paused run's pieces).
double PoolWeight(const ChannelMisfit& m) { return std::max(m.samples, 1); }

}  // namespace

double MedianRunChiSquare(const std::vector<ChannelMisfit>& misfits) {
  // Per run: its channels' and pieces' chi-squares weighted by their rows.
  std::map<std::string, std::pair<double, double>> runs;  // sum of chi2 x rows, rows
  for (const ChannelMisfit& m : misfits) {
    const double rows = PoolWeight(m);
    runs[m.run].first += m.reduced_chi_square * rows;
    runs[m.run].second += rows;
  }
  std::vector<double> values;
  for (const auto& [run, sum] : runs) {
    // A run that could not be simulated is not explained: it counts as the worst.
    values.push_back(std::isnan(sum.first) ? HUGE_VAL : sum.first / sum.second);
  }
  if (values.empty()) return NAN;
  std::sort(values.begin(), values.end());
  const std::size_t half = values.size() / 2;
  return values.size() % 2 ? values[half] : 0.5 * (values[half - 1] + values[half]);
}

namespace {

// The pieces of a run cut at a logger's pause (refine_runs.h, Pieces) as
// one misfit per run and channel: the chi-squares pooled by rows, the worst
// window the worst piece's.
void JoinPieces(std::vector<ChannelMisfit>* misfits) {
  std::vector<ChannelMisfit> joined;
  for (const ChannelMisfit& m : *misfits) {
    auto same = std::find_if(joined.begin(), joined.end(), [&m](const ChannelMisfit& j) {
      return j.run == m.run && j.channel == m.channel;
    });
    if (same == joined.end()) {
      joined.push_back(m);
      continue;
    }
    same->reduced_chi_square =
        (same->reduced_chi_square * PoolWeight(*same) + m.reduced_chi_square * PoolWeight(m)) /
        (PoolWeight(*same) + PoolWeight(m));
    same->samples += m.samples;
    if (m.worst_reduced_chi_square > same->worst_reduced_chi_square) {
      same->worst_reduced_chi_square = m.worst_reduced_chi_square;
      same->worst_from_s = m.worst_from_s;
      same->worst_to_s = m.worst_to_s;
    }
  }
  *misfits = std::move(joined);
}

}  // namespace

void Judge(const RefineOptions& options, RefineResult* r) {
  r->acceptable_reduced_chi_square = options.acceptable_reduced_chi_square;
  JoinPieces(&r->misfits);
  r->reduced_chi_square = MedianRunChiSquare(r->misfits);
  std::sort(r->misfits.begin(), r->misfits.end(),
            [](const ChannelMisfit& a, const ChannelMisfit& b) {
              const bool a_nan = std::isnan(a.reduced_chi_square);
              const bool b_nan = std::isnan(b.reduced_chi_square);
              if (a_nan != b_nan) return a_nan;  // NaN (not simulated) first
              return !a_nan && a.reduced_chi_square > b.reduced_chi_square;
            });
  if (r->status == FitStatus::kNotFitted || r->status == FitStatus::kNotConverged) return;
  if (Explains(r->reduced_chi_square, options)) {
    r->status = FitStatus::kConverged;
    return;
  }
  r->status = FitStatus::kNotExplained;
  char text[400];
  std::snprintf(text, sizeof(text),
                "the model does not explain these logs: the runs' median reduced chi-square is "
                "%.3g, above the acceptable %.3g (1 is the sensor noise alone)",
                r->reduced_chi_square, options.acceptable_reduced_chi_square);
  r->reason = text;
  for (std::size_t k = 0; k < r->misfits.size() && k < 3; ++k) {
    const ChannelMisfit& m = r->misfits[k];
    std::snprintf(text, sizeof(text), "; %s %s: %.3g, worst %.3g over %.3g-%.3g s", m.run.c_str(),
                  m.channel.c_str(), m.reduced_chi_square, m.worst_reduced_chi_square,
                  m.worst_from_s, m.worst_to_s);
    r->reason += text;
  }
}

}  // namespace pneumaid::refine_internal
