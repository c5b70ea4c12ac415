#include "pneumaid/validate/lag_start.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "../util/golden_section.h"
#include "../util/slope.h"
#include "pneumaid/validate/logged_run.h"

namespace pneumaid {
namespace {

// Sample times are sums of rounded periods: 1.32 - 1.3 is 0.02 + 2e-17.
constexpr double kTimeRounding_s = 1e-9;

// The samples within `span_s` of the first (at least one).
std::size_t SamplesWithin(const Trajectory& m, double span_s) {
  std::size_t n = 1;
  while (n < m.size() && m.t_s[n] - m.t_s.front() <= span_s + kTimeRounding_s) ++n;
  return n;
}

// The window's misfit from a command: the mean squared residual of x, p1
// and p2 per their noise over the window's samples after the first (which
// the start is), infinite when the simulation fails.
class WindowMisfit {
 public:
  WindowMisfit(const Parameters& params, const Trajectory& measured, std::size_t n,
               double sigma_x_m, double sigma_p_Pa[2], const SimulationOptions& options)
      : params_(params),
        measured_(measured),
        times_(measured.t_s.begin(), measured.t_s.begin() + static_cast<long>(n)),
        sigma_x_m_(sigma_x_m),
        sigma_p_Pa_{sigma_p_Pa[0], sigma_p_Pa[1]},
        options_(options) {}

  double operator()(const CommandSignal& command, const InitialState& initial) const {
    Trajectory simulated;
    if (!Simulate(params_, command, initial, times_, options_, &simulated).ok() ||
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
  double sigma_x_m_;
  double sigma_p_Pa_[2];
  const SimulationOptions& options_;
};

// A history of commands before a log (lag_start.h): a line through
// (t0, level) of its slope held in kLagHistorySteps steps over
// kLagHistory_s, or a step: settled for the level until ago_s before t0
// (at most kLagHistory_s: longer is settled for the log's first command),
// the log's first command from there. Clamped to +-kLagHistoryCommand_V.
struct History {
  bool step = false;
  double level_V = 0;
  double slope_V_per_s = 0;  // a line's
  double ago_s = 0;          // a step's
  double v = 0;              // the rod's speed at the start [m/s]
  double misfit = std::numeric_limits<double>::infinity();

  // `command` from t0_s on with this history before it.
  CommandSignal Before(const CommandSignal& command, double t0_s) const {
    const double from_s = t0_s - kLagHistory_s;
    const auto clamp = [](double u) {
      return std::clamp(u, -kLagHistoryCommand_V, kLagHistoryCommand_V);
    };
    CommandSignal out;
    if (step) {
      // Settled for the level before from_s (the replay's start), the step
      // after it; a step at or before from_s is settled for the log's first.
      const bool within = ago_s > 0 && ago_s < kLagHistory_s;
      out.initial_V = within ? clamp(level_V) : command.ValueAt(t0_s);
      if (within) {
        out.time_s.push_back(t0_s - ago_s);
        out.value_V.push_back(command.ValueAt(t0_s));
      }
    } else {
      const auto line = [&](double t_s) { return clamp(level_V + slope_V_per_s * (t_s - t0_s)); };
      out.initial_V = line(from_s);
      for (int k = 0; k < kLagHistorySteps; ++k) {
        const double t_s = from_s + kLagHistory_s * k / kLagHistorySteps;
        out.time_s.push_back(t_s);
        out.value_V.push_back(line(t_s));
      }
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

  std::string Describe() const {
    char text[96];
    if (step)
      std::snprintf(text, sizeof(text), "a step from %.3f V %.0f ms before the log", level_V,
                    ago_s * 1e3);
    else
      std::snprintf(text, sizeof(text), "a command through %.3f V at %+.3f V/s", level_V,
                    slope_V_per_s);
    return text;
  }
};

// Golden section on one coordinate of `h` over [low, high] (in `scale`'s
// coordinate), kept where it lowers the misfit.
template <typename Cost, typename Scale>
void Refined(const Cost& cost, double History::*coordinate, double low, double high,
             const Scale& scale, History* h) {
  const internal::GoldenSectionMinimum found = internal::GoldenSection(
      [&](double c) {
        History trial = *h;
        trial.*coordinate = scale(c);
        return cost(trial);
      },
      low, high, 12);
  if (found.value < h->misfit) h->*coordinate = scale(found.x), h->misfit = found.value;
}

double NoiseOf(const std::map<std::string, double>& noise, const char* channel) {
  const auto found = noise.find(channel);
  return found == noise.end() ? 0.0 : found->second;
}

}  // namespace

// Over its samples before the command
// changes (beyond the logger's noise; at most kLagStartSettle_s) the rod
// moves 0.1 mm, a pressure leaves the start's band, or a pressure drifts
// (its slope over kLagStartDriftSigmas standard errors). A command that
// changes at once is a log that starts at its step (LoggedCommand's rule):
// settled before it, not read.
bool StartsUnsettled(const Trajectory& m) {
  std::size_t n = 1;
  while (n < m.size() && m.t_s[n] - m.t_s.front() <= kLagStartSettle_s + kTimeRounding_s &&
         std::fabs(m.u_V[n] - m.u_V[0]) <= kCommandNoise_V)
    ++n;
  if (n < 2) return false;
  for (std::size_t i = 1; i < n; ++i) {
    if (std::fabs(m.x_m[i] - m.x_m[0]) > kMovedAtStart_m ||
        std::fabs(m.p1_Pa[i] - m.p1_Pa[0]) > kStartPressureBand_Pa ||
        std::fabs(m.p2_Pa[i] - m.p2_Pa[0]) > kStartPressureBand_Pa) {
      return true;
    }
  }
  // A residual under 1 Pa is a logger's rounding, not a measure of noise.
  return internal::LeadingSlopeSigmas(m.t_s, m.p1_Pa, n, 1.0) > kLagStartDriftSigmas ||
         internal::LeadingSlopeSigmas(m.t_s, m.p2_Pa, n, 1.0) > kLagStartDriftSigmas;
}

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
  if (n < 3 || !StartsUnsettled(m)) return out;
  const WindowMisfit misfit(params, m, n, sigma_x_m, sigma_p_Pa, options);
  out.misfit_given = misfit(command, initial);
  if (!(out.misfit_given > kLagStartMisfit)) return out;
  const auto identity = [](double c) { return c; };
  const auto exponential = [](double c) { return std::exp(c); };
  // A moving start's speed (read off 5 ms of x: a slow slide's noise or a
  // stick-slip reads it off by tens of mm/s) refined with the logged
  // command first: a history must do better than that.
  const double speed_span =
      std::max(kLagStartSpeedSpan_m_per_s, std::fabs(initial.velocity_m_per_s));
  InitialState sped = initial;
  double given = out.misfit_given;
  if (initial.velocity_m_per_s != 0) {
    const internal::GoldenSectionMinimum found = internal::GoldenSection(
        [&](double v) {
          InitialState start = initial;
          start.velocity_m_per_s = v;
          return misfit(command, start);
        },
        initial.velocity_m_per_s - speed_span, initial.velocity_m_per_s + speed_span, 12);
    if (found.value < given) sped.velocity_m_per_s = found.x, given = found.value;
  }
  InitialState replayed = sped;
  replayed.lag_history_from_s = t0_s - kLagHistory_s;
  const auto cost = [&](const History& h) {
    InitialState start = replayed;
    start.velocity_m_per_s = h.v;
    return misfit(h.Before(command, t0_s), start);
  };
  // Lines: from the best settled level (slope 0) and from the logged
  // command's own line, the level and the slope in turn.
  const auto a_line = [&](double level_V, double slope_V_per_s) {
    History h;
    h.level_V = level_V, h.slope_V_per_s = slope_V_per_s, h.v = sped.velocity_m_per_s;
    h.misfit = cost(h);
    return h;
  };
  History settled;
  for (int k = -10; k <= 10; ++k) {
    const History h = a_line(0.1 * k, 0.0);
    if (h.misfit < settled.misfit) settled = h;
  }
  const History logged = a_line(m.u_V.front(), internal::LeadingSlope(m.t_s, m.u_V, n));
  const double slope_span = std::max(1.0, std::fabs(logged.slope_V_per_s));
  History best;
  for (History h : {settled, logged}) {
    for (int round = 0; round < kLagStartRounds; ++round) {
      Refined(cost, &History::level_V, h.level_V - 0.1, h.level_V + 0.1, identity, &h);
      Refined(cost, &History::slope_V_per_s, h.slope_V_per_s - slope_span,
              h.slope_V_per_s + slope_span, identity, &h);
    }
    if (h.misfit < best.misfit) best = h;
  }
  // Steps: a grid of levels and times before the log, then each in turn
  // (the time in its logarithm, across a grid step either side).
  History step;
  for (int k = -10; k <= 10; ++k) {
    for (double ago_s = 0.005; ago_s < kLagHistory_s; ago_s *= 2) {
      History h;
      h.step = true, h.level_V = 0.1 * k, h.ago_s = ago_s, h.v = sped.velocity_m_per_s;
      h.misfit = cost(h);
      if (h.misfit < step.misfit) step = h;
    }
  }
  for (int round = 0; round < kLagStartRounds && step.ago_s > 0; ++round) {
    Refined(cost, &History::level_V, step.level_V - 0.1, step.level_V + 0.1, identity, &step);
    // Up to the history's length (a step as long ago is settled).
    Refined(cost, &History::ago_s, std::log(step.ago_s / 2),
            std::min(std::log(step.ago_s * 2), std::log(kLagHistory_s)), exponential, &step);
  }
  if (step.misfit < best.misfit) best = step;
  // The speed with the history.
  for (int round = 0; round < kLagStartRounds && initial.velocity_m_per_s != 0; ++round) {
    Refined(cost, &History::v, best.v - speed_span, best.v + speed_span, identity, &best);
    Refined(cost, &History::level_V, best.level_V - 0.1, best.level_V + 0.1, identity, &best);
  }
  // A read must hold beyond the window it was read from: over the first
  // kLagStartConfirm_s it must fit better than the start it replaces (a
  // history that bends the window to an error of the start's own state
  // drifts off after it).
  const WindowMisfit confirm(params, m, SamplesWithin(m, kLagStartConfirm_s), sigma_x_m, sigma_p_Pa,
                             options);
  const double given_after = confirm(command, initial);
  const auto holds = [&](const CommandSignal& c, const InitialState& start) {
    return confirm(c, start) < given_after;
  };
  InitialState best_start = replayed;
  best_start.velocity_m_per_s = best.v;
  char line[320];
  if (best.misfit < kLagStartKeepRatio * given && holds(best.Before(command, t0_s), best_start)) {
    out.misfit_read = best.misfit;
    out.command = best.Before(command, t0_s);
    out.initial = replayed;
    out.initial.velocity_m_per_s = best.v;
    std::snprintf(line, sizeof(line),
                  "the log starts unsettled (%.3f V): the valves' lags read off its first %.0f ms "
                  "as after %s, its speed %.4g m/s (misfit %.3g -> %.3g per residual)",
                  m.u_V.front(), kLagStartWindow_s * 1e3, best.Describe().c_str(), best.v,
                  out.misfit_given, best.misfit);
  } else if (given < kLagStartKeepRatio * out.misfit_given && holds(command, sped)) {
    out.misfit_read = given;
    out.command = command;
    out.initial = sped;
    std::snprintf(line, sizeof(line),
                  "the log starts unsettled (%.3f V): its speed read off its first %.0f ms, "
                  "%.4g m/s (misfit %.3g -> %.3g per residual); the lags as logged",
                  m.u_V.front(), kLagStartWindow_s * 1e3, sped.velocity_m_per_s, out.misfit_given,
                  given);
  } else {
    out.misfit_read = std::min(best.misfit, given);
    return out;
  }
  out.read = true;
  out.note = line;
  return out;
}

}  // namespace pneumaid
