#include "pneumaid/validate/lag_start.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

#include "../util/golden_section.h"
#include "../util/slope.h"
#include "pneumaid/validate/logged_run.h"

namespace pneumaid {
namespace {

// The samples within `span_s` of the first (at least one).
std::size_t SamplesWithin(const Trajectory& m, double span_s) {
  std::size_t n = 1;
  while (n < m.size() && m.t_s[n] - m.t_s.front() <= span_s) ++n;
  return n;
}

// Whether the run starts not settled: within kLagStartSettle_s the rod moves
// or a pressure changes beyond the band the start's averaging allows.
bool StartsUnsettled(const Trajectory& m) {
  const std::size_t n = SamplesWithin(m, kLagStartSettle_s);
  for (std::size_t i = 1; i < n; ++i) {
    if (std::fabs(m.x_m[i] - m.x_m[0]) > kMovedAtStart_m ||
        std::fabs(m.p1_Pa[i] - m.p1_Pa[0]) > kStartPressureBand_Pa ||
        std::fabs(m.p2_Pa[i] - m.p2_Pa[0]) > kStartPressureBand_Pa) {
      return true;
    }
  }
  return false;
}

bool CommandChanges(const Trajectory& m, std::size_t n) {
  for (std::size_t i = 1; i < n; ++i) {
    if (std::fabs(m.u_V[i] - m.u_V[0]) > kCommandNoise_V) return true;
  }
  return false;
}

// The window's misfit from a command: the mean squared residual of x, p1
// and p2 per their noise over the window's samples after the first (which
// the start is), infinite when the simulation fails.
class WindowMisfit {
 public:
  WindowMisfit(const Parameters& params, const Trajectory& measured, std::size_t n,
               const InitialState& initial, double sigma_x_m, double sigma_p_Pa[2],
               const SimulationOptions& options)
      : params_(params),
        measured_(measured),
        times_(measured.t_s.begin(), measured.t_s.begin() + static_cast<long>(n)),
        initial_(initial),
        sigma_x_m_(sigma_x_m),
        sigma_p_Pa_{sigma_p_Pa[0], sigma_p_Pa[1]},
        options_(options) {}

  double operator()(const CommandSignal& command) const {
    Trajectory simulated;
    if (!Simulate(params_, command, initial_, times_, options_, &simulated).ok() ||
        simulated.size() != times_.size()) {
      return std::numeric_limits<double>::infinity();
    }
    double sum = 0;
    for (std::size_t i = 1; i < times_.size(); ++i) {
      const double rx = (simulated.x_m[i] - measured_.x_m[i]) / sigma_x_m_;
      const double r1 = (simulated.p1_Pa[i] - measured_.p1_Pa[i]) / sigma_p_Pa_[0];
      const double r2 = (simulated.p2_Pa[i] - measured_.p2_Pa[i]) / sigma_p_Pa_[1];
      sum += rx * rx + r1 * r1 + r2 * r2;
    }
    return sum / (3.0 * static_cast<double>(times_.size() - 1));
  }

 private:
  const Parameters& params_;
  const Trajectory& measured_;
  std::vector<double> times_;
  const InitialState& initial_;
  double sigma_x_m_;
  double sigma_p_Pa_[2];
  const SimulationOptions& options_;
};

// `command` from t0_s on, before it a line through (t0_s, level_V) with
// slope_V_per_s, held in kLagHistorySteps steps over kLagHistory_s and
// clamped to +-kLagHistoryCommand_V; settled for the line's start before.
CommandSignal WithHistory(const CommandSignal& command, double t0_s, double level_V,
                          double slope_V_per_s) {
  const auto line = [&](double t_s) {
    return std::clamp(level_V + slope_V_per_s * (t_s - t0_s), -kLagHistoryCommand_V,
                      kLagHistoryCommand_V);
  };
  CommandSignal out;
  const double from_s = t0_s - kLagHistory_s;
  out.initial_V = line(from_s);
  for (int k = 0; k < kLagHistorySteps; ++k) {
    const double t_s = from_s + kLagHistory_s * k / kLagHistorySteps;
    out.time_s.push_back(t_s);
    out.value_V.push_back(line(t_s));
  }
  out.time_s.push_back(t0_s);
  out.value_V.push_back(command.ValueAt(t0_s));
  for (std::size_t k = 0; k < command.time_s.size(); ++k) {
    if (command.time_s[k] <= t0_s) continue;
    out.time_s.push_back(command.time_s[k]);
    out.value_V.push_back(command.value_V[k]);
  }
  return out;
}

double NoiseOf(const std::map<std::string, double>& noise, const char* channel) {
  const auto found = noise.find(channel);
  return found == noise.end() ? 0.0 : found->second;
}

}  // namespace

LagStart ReadLagStart(const Parameters& params, const Trajectory& m, const CommandSignal& command,
                      const InitialState& initial, const std::map<std::string, double>& noise,
                      const SimulationOptions& options) {
  LagStart out;
  double sigma_p_Pa[2] = {NoiseOf(noise, "p1"), NoiseOf(noise, "p2")};
  const double sigma_x_m = NoiseOf(noise, "x");
  if (m.size() < 3 || m.x_m.size() != m.size() || m.p1_Pa.size() != m.size() ||
      m.p2_Pa.size() != m.size() || m.u_V.size() != m.size() ||
      !(sigma_x_m > 0 && sigma_p_Pa[0] > 0 && sigma_p_Pa[1] > 0)) {
    return out;
  }
  const double t0_s = m.t_s.front();
  const std::size_t n = SamplesWithin(m, kLagStartWindow_s);
  if (n < 3 || !CommandChanges(m, n) || !StartsUnsettled(m)) return out;
  const WindowMisfit misfit(params, m, n, initial, sigma_x_m, sigma_p_Pa, options);
  out.misfit_given = misfit(command);
  if (!(out.misfit_given > kLagStartMisfit)) return out;
  // The history: a line through (t0, level) of the given slope over the
  // last kLagHistory_s, the lags settled at its start.
  const auto history = [&](double level_V, double slope_V_per_s) {
    return WithHistory(command, t0_s, level_V, slope_V_per_s);
  };
  InitialState replayed = initial;
  replayed.lag_history_from_s = t0_s - kLagHistory_s;
  const WindowMisfit misfit_replayed(params, m, n, replayed, sigma_x_m, sigma_p_Pa, options);
  const auto cost = [&](double level_V, double slope_V_per_s) {
    return misfit_replayed(history(level_V, slope_V_per_s));
  };
  // Two starts: the best settled level (slope 0) and the logged command's
  // own line; from each, the level and the slope in turn by golden section
  // (12 steps shrink a bracket 0.003 times). The better end is kept.
  struct Point {
    double level_V, slope_V_per_s, misfit;
  };
  Point settled{0, 0, std::numeric_limits<double>::infinity()};
  for (int k = -10; k <= 10; ++k) {
    const double value = cost(0.1 * k, 0.0);
    if (value < settled.misfit) settled = {0.1 * k, 0.0, value};
  }
  const double logged_slope = internal::LeadingSlope(m.t_s, m.u_V, n);
  const Point logged{m.u_V.front(), logged_slope, cost(m.u_V.front(), logged_slope)};
  const double slope_span = std::max(1.0, std::fabs(logged_slope));
  Point best{0, 0, std::numeric_limits<double>::infinity()};
  for (Point p : {settled, logged}) {
    for (int round = 0; round < kLagStartRounds; ++round) {
      const internal::GoldenSectionMinimum by_level = internal::GoldenSection(
          [&](double v) { return cost(v, p.slope_V_per_s); }, p.level_V - 0.1, p.level_V + 0.1, 12);
      if (by_level.value < p.misfit) p.level_V = by_level.x, p.misfit = by_level.value;
      const internal::GoldenSectionMinimum by_slope =
          internal::GoldenSection([&](double v) { return cost(p.level_V, v); },
                                  p.slope_V_per_s - slope_span, p.slope_V_per_s + slope_span, 12);
      if (by_slope.value < p.misfit) p.slope_V_per_s = by_slope.x, p.misfit = by_slope.value;
    }
    if (p.misfit < best.misfit) best = p;
  }
  const double level_V = best.level_V, slope_V_per_s = best.slope_V_per_s;
  out.misfit_read = best.misfit;
  if (!(best.misfit < kLagStartKeepRatio * out.misfit_given)) return out;
  out.read = true;
  out.command = history(level_V, slope_V_per_s);
  out.initial = replayed;
  char line[320];
  std::snprintf(line, sizeof(line),
                "the log starts unsettled under a changing command (%.3f V): the valves' lags "
                "read off its first %.0f ms as after a command through %.3f V at %+.3f V/s "
                "(misfit %.3g -> %.3g per residual)",
                m.u_V.front(), kLagStartWindow_s * 1e3, level_V, slope_V_per_s, out.misfit_given,
                best.misfit);
  out.note = line;
  return out;
}

}  // namespace pneumaid
