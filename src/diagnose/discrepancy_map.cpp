#include "discrepancy_map.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "pneumaid/io/channel_noise.h"

namespace pneumaid::diagnose_internal {
namespace {

constexpr double kShut_V = 0.02;         // |u| below this: valves shut
constexpr double kSmallOpening_V = 0.3;  // |u| below this (and open): a small opening
constexpr double kChange_V = 0.02;       // a command step larger than this is a change
constexpr double kStuckSpeed_m_per_s = 2e-3;
constexpr double kEndZone_m = 5e-4;
constexpr double kSpeedWindow_s = 0.005;  // half-width of the speed estimate

// The regime bits of every sample of a logged run.
std::vector<unsigned> Regimes(const Trajectory& run, double half_stroke_m,
                              const DiagnoseOptions& options) {
  const std::size_t n = run.size();
  std::vector<unsigned> bits(n, kAllSamples);
  double last_change = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    const double u = run.u_V[i], t = run.t_s[i];
    if (i > 0 && std::fabs(u - run.u_V[i - 1]) > kChange_V) last_change = t;
    const bool after_change = t - last_change < options.after_change_s;
    if (after_change) bits[i] |= kAfterChange;
    if (u > kShut_V) bits[i] |= kExtendCommand;
    if (u < -kShut_V) bits[i] |= kRetractCommand;
    if (std::fabs(u) <= kShut_V && !after_change) bits[i] |= kValvesShut;
    if (std::fabs(u) > kShut_V && std::fabs(u) < kSmallOpening_V) bits[i] |= kSmallOpening;
    if (run.x_m.empty()) continue;
    if (std::fabs(run.x_m[i]) >= half_stroke_m - kEndZone_m) {
      bits[i] |= kAtEndStop;
      continue;
    }
    std::size_t a = i, b = i;
    while (a > 0 && run.t_s[i] - run.t_s[a - 1] <= kSpeedWindow_s) --a;
    while (b + 1 < n && run.t_s[b + 1] - run.t_s[i] <= kSpeedWindow_s) ++b;
    const double speed =
        b > a ? std::fabs(run.x_m[b] - run.x_m[a]) / (run.t_s[b] - run.t_s[a]) : 0.0;
    bits[i] |= speed < kStuckSpeed_m_per_s ? kStuck : kSliding;
  }
  return bits;
}

struct Accumulator {
  long samples = 0;
  double sum = 0, squares = 0;
  void Add(double r) {
    ++samples;
    sum += r;
    squares += r * r;
  }
};

}  // namespace

const char* RegimeName(int bit_index) {
  static const char* const kNames[kRegimeCount] = {"all samples",
                                                   "extend command (u > 0)",
                                                   "retract command (u < 0)",
                                                   "valves shut",
                                                   "small opening",
                                                   "first stretch after a command change",
                                                   "sliding",
                                                   "stuck",
                                                   "at an end stop"};
  return bit_index >= 0 && bit_index < kRegimeCount ? kNames[bit_index] : "?";
}

double ChannelSums::MeanSquare(const std::string& channel) const {
  const auto n = samples.find(channel);
  if (n == samples.end() || n->second == 0) return NAN;
  return squares.at(channel) / static_cast<double>(n->second);
}

void ChannelSums::Add(const ChannelSums& other) {
  for (const auto& [channel, value] : other.squares) squares[channel] += value;
  for (const auto& [channel, value] : other.samples) samples[channel] += value;
}

std::map<std::string, ChannelSums> RunSums(const ValidationReport& report) {
  std::map<std::string, ChannelSums> out;
  for (const ExperimentValidation& e : report.experiments) {
    ChannelSums& sums = out[e.id];
    for (const TrajectoryChannel& channel : kComparedChannels) {
      const auto& measured = e.measured.*(channel.values);
      const auto& simulated = e.simulated.*(channel.values);
      if (measured.empty()) continue;
      if (!e.simulation.ok() || simulated.size() != measured.size()) {
        sums.squares[channel.name] = INFINITY;
        sums.samples[channel.name] = static_cast<long>(measured.size());
        continue;
      }
      double squares = 0;
      for (std::size_t i = 0; i < measured.size(); ++i) {
        squares += (measured[i] - simulated[i]) * (measured[i] - simulated[i]);
      }
      sums.squares[channel.name] = squares;
      sums.samples[channel.name] = static_cast<long>(measured.size());
    }
  }
  return out;
}

ChannelSums Pool(const std::map<std::string, ChannelSums>& per_run,
                 const std::vector<std::string>& runs) {
  ChannelSums pooled;
  for (const std::string& run : runs) {
    const auto found = per_run.find(run);
    if (found != per_run.end()) pooled.Add(found->second);
  }
  return pooled;
}

double NormalisedCost(const ChannelSums& sums, const std::map<std::string, double>& scale) {
  double cost = 0;
  for (const auto& [channel, variance] : scale) {
    const double ms = sums.MeanSquare(channel);
    if (variance > 0 && !std::isnan(ms)) cost += ms / variance;
  }
  return cost;
}

DiscrepancyMap MapDiscrepancy(const ValidationReport& report, const Unit& unit,
                              double half_stroke_m, const DiagnoseOptions& options) {
  DiscrepancyMap map;
  std::map<std::pair<std::string, int>, Accumulator> by_regime;
  std::map<std::string, Accumulator> by_channel;
  for (const TrajectoryChannel& channel : kComparedChannels)
    map.noise[channel.name] = NoiseSigma(unit, channel.name);
  for (const ExperimentValidation& e : report.experiments) {
    if (!e.simulation.ok()) continue;
    const std::vector<unsigned> regimes = Regimes(e.measured, half_stroke_m, options);
    for (const TrajectoryChannel& channel : kComparedChannels) {
      const auto& measured = e.measured.*(channel.values);
      const auto& simulated = e.simulated.*(channel.values);
      if (measured.empty() || simulated.size() != measured.size()) continue;
      Accumulator window;
      double window_start = e.measured.t_s.front();
      const auto close_window = [&](double end) {
        if (window.samples == 0) return;
        ResidualWindow w{e.id,
                         channel.name,
                         window_start,
                         end,
                         std::sqrt(window.squares / window.samples),
                         window.sum / window.samples};
        map.worst.push_back(w);
        window = Accumulator{};
      };
      for (std::size_t i = 0; i < measured.size(); ++i) {
        const double r = measured[i] - simulated[i];
        by_channel[channel.name].Add(r);
        for (int bit = 0; bit < kRegimeCount; ++bit) {
          if (regimes[i] & (1u << bit)) by_regime[{channel.name, bit}].Add(r);
        }
        if (e.measured.t_s[i] - window_start >= options.window_s) {
          close_window(e.measured.t_s[i]);
          window_start = e.measured.t_s[i];
        }
        window.Add(r);
      }
      close_window(e.measured.t_s.back());
    }
  }
  for (const auto& [key, a] : by_regime) {
    RegimeResidual r;
    r.channel = key.first;
    r.regime = RegimeName(key.second);
    r.samples = a.samples;
    r.rmse = std::sqrt(a.squares / a.samples);
    r.mean = a.sum / a.samples;
    const double noise = map.noise[key.first];
    r.reduced_chi_square = noise > 0 ? r.rmse * r.rmse / (noise * noise) : 0.0;
    map.regimes.push_back(r);
  }
  for (const auto& [channel, a] : by_channel) map.rmse[channel] = std::sqrt(a.squares / a.samples);
  // Worst windows: each window's RMSE in units of its channel's whole-run
  // RMSE (so that pressures in Pa and positions in m compare).
  std::sort(map.worst.begin(), map.worst.end(),
            [&map](const ResidualWindow& a, const ResidualWindow& b) {
              return a.rmse / std::max(map.rmse[a.channel], 1e-300) >
                     b.rmse / std::max(map.rmse[b.channel], 1e-300);
            });
  if (static_cast<int>(map.worst.size()) > options.worst_windows)
    map.worst.resize(static_cast<std::size_t>(options.worst_windows));
  return map;
}

}  // namespace pneumaid::diagnose_internal
