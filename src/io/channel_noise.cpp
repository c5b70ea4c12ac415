#include "pneumaid/io/channel_noise.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

#include "../util/median.h"
#include "pneumaid/io/log_notes.h"

namespace pneumaid {
namespace {

// At most this many fourth differences are read per estimate (evenly strided
// over the logs): the spread of 50 000 is known to 0.5 %, and a unit logged at
// 5 kHz holds millions.
constexpr std::size_t kMaxDifferences = 50000;

// The ADC step the readings lie on: the smallest non-zero step between two
// readings, when at least 99 % of the steps are whole multiples of it (to
// 1e-4 of it: the readings went through a unit conversion; a glitch or an
// interpolated sample may not be) and it occurs at least ten times (a single
// jump or a handful of set points is no ADC); 0 otherwise.
double Quantum(const std::vector<const std::vector<double>*>& columns, std::size_t stride) {
  double smallest = HUGE_VAL;
  for (const std::vector<double>* v : columns) {
    for (std::size_t i = 1; i < v->size(); i += stride) {
      const double step = std::fabs((*v)[i] - (*v)[i - 1]);
      if (step > 0) smallest = std::min(smallest, step);
    }
  }
  if (!std::isfinite(smallest)) return 0;
  std::size_t steps = 0, off_grid = 0, unit_steps = 0;
  for (const std::vector<double>* v : columns) {
    for (std::size_t i = 1; i < v->size(); i += stride) {
      const double multiple = std::fabs((*v)[i] - (*v)[i - 1]) / smallest;
      if (multiple == 0) continue;
      ++steps;
      off_grid += std::fabs(multiple - std::round(multiple)) > 1e-4;
      unit_steps += std::round(multiple) == 1;
    }
  }
  return 100 * off_grid <= steps && unit_steps >= 10 ? smallest : 0.0;
}

// The fourth difference centred on *y (y[-2] .. y[2]): white noise of sigma
// has variance kFourthDifferenceVariance sigma^2 in it.
constexpr double kFourthDifferenceVariance = 70.0;
double FourthDifference(const double* y) { return y[2] - 4 * y[1] + 6 * y[0] - 4 * y[-1] + y[-2]; }

// The same of a log sampled at the irregular times *t (t[-2] .. t[2]): the
// fourth divided difference, which cancels any cubic in time (by index, a
// slide at 0.1 m/s on a clock with +-40 % jitter left tens of um: x's noise
// read twice the truth's), scaled so that white noise again has variance
// kFourthDifferenceVariance sigma^2 in it; FourthDifference on a uniform clock.
double FourthDividedDifference(const double* y, const double* t) {
  double weights[5], sum = 0, squares = 0;
  for (int k = 0; k < 5; ++k) {
    double product = 1;
    for (int j = 0; j < 5; ++j)
      if (j != k) product *= t[k - 2] - t[j - 2];
    weights[k] = 1 / product;
    sum += weights[k] * y[k - 2];
    squares += weights[k] * weights[k];
  }
  return sum * std::sqrt(kFourthDifferenceVariance / squares);
}

// The differences of one logged column: by index on a uniform clock, divided
// by the logged times otherwise.
struct Differencer {
  const std::vector<double>& y;
  const std::vector<double>* t;  // null: uniform

  Differencer(const std::vector<double>& values, const std::vector<double>* times)
      : y(values), t(Irregular(times, values.size()) ? times : nullptr) {}

  double operator()(std::size_t i) const {
    return t == nullptr ? FourthDifference(y.data() + i)
                        : FourthDividedDifference(y.data() + i, t->data() + i);
  }

  // Times that exist for every value and lie on no uniform grid (a clock
  // that keeps no time, or one that lost rows: across a lost row the index
  // does not cancel a slide either). A grid stamped with jitter is sampled
  // on the grid: by index.
  static bool Irregular(const std::vector<double>* t, std::size_t n) {
    return t != nullptr && t->size() == n && n >= 5 && UniformPeriod(*t) <= 0;
  }
};

// The time column of the k-th of `columns` (null: none given).
const std::vector<double>* TimesOf(const std::vector<const std::vector<double>*>& times,
                                   std::size_t k) {
  return k < times.size() ? times[k] : nullptr;
}

// The sigma of white noise whose fourth differences have these magnitudes:
// their median is 0.6745 of the differences' sigma.
double SigmaOfDifferences(std::vector<double> magnitudes) {
  return internal::Median(std::move(magnitudes)) / 0.6745 / std::sqrt(kFourthDifferenceVariance);
}

// The quietest stretches of `columns`: the fourth differences in blocks of
// kFloorBlock samples, each block's spread (SigmaOfDifferences). Where the signal is not smooth at
// the sampling rate (a light rod slipping within a sample at 250 Hz) EstimateNoise reads its moves
// as noise; a resting rod, a settled chamber or a held flow shows the noise alone.
constexpr std::size_t kFloorBlock = 64;
// A floor over fewer blocks than this is no percentile.
constexpr std::size_t kMinFloorBlocks = 20;
struct Blocks {
  std::vector<double> spreads;      // one per block
  std::vector<double> differences;  // |fourth differences|, kFloorBlock - 4 per block
};
Blocks BlocksOf(const std::vector<const std::vector<double>*>& columns,
                const std::vector<const std::vector<double>*>& times) {
  Blocks out;
  for (std::size_t k = 0; k < columns.size(); ++k) {
    const std::vector<double>* v = columns[k];
    const Differencer difference(*v, TimesOf(times, k));
    for (std::size_t begin = 0; begin + kFloorBlock <= v->size(); begin += kFloorBlock) {
      for (std::size_t i = begin + 2; i + 2 < begin + kFloorBlock; ++i)
        out.differences.push_back(std::fabs(difference(i)));
      out.spreads.push_back(
          SigmaOfDifferences({out.differences.end() - (kFloorBlock - 4), out.differences.end()}));
    }
  }
  return out;
}

// The 10th percentile of the blocks' spreads (0 for too few blocks).
double TenthPercentile(std::vector<double> spreads) {
  if (spreads.size() < kMinFloorBlocks) return 0;
  const std::size_t at = spreads.size() / 10;
  std::nth_element(spreads.begin(), spreads.begin() + at, spreads.end());
  return spreads[at];
}

// A floor under the noise of `columns`: the 10th percentile of the blocks'
// spreads (0.785 of sigma for white noise; lower where a quiet block lies on
// one ADC level). What ChannelNoiseNote holds a declared noise against.
double QuietNoiseFloor(const std::vector<const std::vector<double>*>& columns,
                       const std::vector<const std::vector<double>*>& times) {
  return TenthPercentile(BlocksOf(columns, times).spreads);
}

// The noise of the quiet stretches of `columns`: the fourth differences of
// every block whose spread is within kQuietBand of the floor, pooled (their
// median absolute value), over what that gives on white noise. Unbiased
// whatever share of the log is quiet, where the floor alone is not: with 30 %
// of the blocks quiet the 10th percentile over all of them is a third of the
// way up the quiet ones' (a reading 18 % high).
constexpr double kQuietBand = 2.0;
// Measured on 40 logs of 8000 Gaussian samples: 0.989 of sigma on white
// noise, 0.998 where 30 % of the blocks are quiet.
constexpr double kQuietOfWhiteNoise = 0.989;
double QuietNoise(const std::vector<const std::vector<double>*>& columns,
                  const std::vector<const std::vector<double>*>& times) {
  const Blocks blocks = BlocksOf(columns, times);
  const double floor = TenthPercentile(blocks.spreads);
  if (!(floor > 0)) return 0;
  std::vector<double> pooled;
  const std::size_t per_block = kFloorBlock - 4;
  for (std::size_t k = 0; k < blocks.spreads.size(); ++k) {
    if (blocks.spreads[k] > kQuietBand * floor) continue;
    const auto first = blocks.differences.begin() + static_cast<std::ptrdiff_t>(k * per_block);
    pooled.insert(pooled.end(), first, first + static_cast<std::ptrdiff_t>(per_block));
  }
  return SigmaOfDifferences(std::move(pooled)) / kQuietOfWhiteNoise;
}

const char* SiUnit(const std::string& column) {
  if (column == "x") return "m";
  if (column == "u") return "V";
  if (column.rfind("p", 0) == 0) return "Pa";
  if (column.rfind("q", 0) == 0) return "kg/s";
  return "";
}

}  // namespace

ChannelNoise EstimateNoise(const std::vector<const std::vector<double>*>& columns,
                           const std::vector<const std::vector<double>*>& times) {
  std::size_t total = 0;
  for (const std::vector<double>* v : columns) total += v->size() > 4 ? v->size() - 4 : 0;
  ChannelNoise noise;
  if (total == 0) return noise;
  const std::size_t stride = (total + kMaxDifferences - 1) / kMaxDifferences;
  // Fourth differences: white noise of sigma has variance 70 sigma^2 in them,
  // and a signal sampled ten times faster than it changes is 10^4 times
  // smaller than in the readings (second differences leave a rod's strokes
  // and the chambers' transients at 1 kHz 10 to 60 % above the noise).
  std::vector<double> d4;
  d4.reserve(total / stride + columns.size());
  for (std::size_t k = 0; k < columns.size(); ++k) {
    const std::vector<double>& y = *columns[k];
    const Differencer difference(y, TimesOf(times, k));
    for (std::size_t i = 2; i + 2 < y.size(); i += stride) d4.push_back(difference(i));
  }
  noise.samples = d4.size();
  noise.quantum = Quantum(columns, stride);
  std::vector<double> magnitude(d4.size());
  std::transform(d4.begin(), d4.end(), magnitude.begin(), [](double d) { return std::fabs(d); });
  double median = internal::Median(magnitude);
  if (median == 0) {  // at rest more than half the time: the scale of the moves
    std::vector<double> moves;
    for (double m : magnitude)
      if (m > 0) moves.push_back(m);
    if (!moves.empty()) median = internal::Median(std::move(moves));
  }
  // A trimmed second moment rather than the median alone: on readings that
  // lie on a coarse ADC step the median of |d4| is a whole number of steps.
  // Beyond the cut: transients, steps, impacts (the signal, not its noise).
  // On an ADC step a resting signal's differences are 0 up to the rounding of
  // the unit conversion: the cut is then two steps.
  const double cut = std::max(5 * 1.4826 * median, 2 * noise.quantum);
  double squares = 0;
  std::size_t kept = 0;
  for (double d : d4) {
    if (std::fabs(d) <= cut) {
      squares += d * d;
      ++kept;
    }
  }
  const double spread =
      kept > 0 ? squares / (kFourthDifferenceVariance * static_cast<double>(kept)) : 0.0;
  // Readings on an ADC step: a model is off by the rounding, q^2 / 12 in
  // variance, also where the differences do not see it (a resting signal with
  // less noise than the step repeats its reading). Where the noise is at least
  // about half the step the differences see noise and rounding both.
  noise.sigma = std::sqrt(std::max(spread, noise.quantum * noise.quantum / 12));
  // Where the quietest stretches show less than half of that, the spread is
  // the signal's: not smooth at the sampling rate (a light rod that slips
  // within a sample at 250 Hz: 983 Pa on pressures of 300 Pa noise). Not on
  // readings whose noise is below half their ADC step: a quiet stretch there
  // repeats its reading and shows the rounding, not the noise.
  const double quiet = QuietNoise(columns, times);
  if (quiet > 0 && quiet >= 0.5 * noise.quantum && 2 * quiet < noise.sigma) {
    noise.sigma = std::max(quiet, noise.quantum / std::sqrt(12.0));
  }
  // A log written with about six significant digits is known no better.
  double largest = 0;
  for (const std::vector<double>* v : columns)
    for (double value : *v) largest = std::max(largest, std::fabs(value));
  if (noise.sigma > 0) noise.sigma = std::max(noise.sigma, 1e-6 * largest);
  return noise;
}

ChannelNoise NoiseOf(const Manifest& manifest, const std::string& column,
                     const std::vector<const std::vector<double>*>& logs,
                     const std::vector<const std::vector<double>*>& times) {
  const auto declared = manifest.sensors.find(column);
  if (declared == manifest.sensors.end() || !declared->second.sigma)
    return EstimateNoise(logs, times);
  ChannelNoise noise;
  noise.sigma = *declared->second.sigma;
  noise.declared = true;
  return noise;
}

namespace {

// The column's samples in every log of the unit that has it, and their times.
struct LoggedColumns {
  std::vector<const std::vector<double>*> values, times;

  LoggedColumns(const Unit& unit, const std::string& column) {
    for (const Experiment& e : unit.experiments) {
      if (e.column(column).empty()) continue;
      values.push_back(&e.column(column));
      times.push_back(&e.column("t"));
    }
  }
};

}  // namespace

ChannelNoise NoiseOf(const Unit& unit, const std::string& column) {
  const LoggedColumns logged(unit, column);
  return NoiseOf(unit.manifest, column, logged.values, logged.times);
}

double NoiseSigma(const Unit& unit, const std::string& column) {
  return NoiseOf(unit, column).sigma;
}

std::string ChannelNoiseNote(const Unit& unit, const std::vector<std::string>& columns) {
  std::string estimated, contradicted;
  for (const std::string& column : columns) {
    const ChannelNoise noise = NoiseOf(unit, column);
    char item[160];
    if (!noise.declared) {
      if (noise.samples == 0) continue;
      std::snprintf(item, sizeof(item), "%s%s %.3g %s", estimated.empty() ? "" : ", ",
                    column.c_str(), noise.sigma, SiUnit(column));
      estimated += item;
      continue;
    }
    const LoggedColumns columns_logged(unit, column);
    const double logged = QuietNoiseFloor(columns_logged.values, columns_logged.times);
    if (!(logged > kDeclaredNoiseContradicted * noise.sigma)) continue;
    std::snprintf(item, sizeof(item), "%s%s %.3g %s declared, the logs' quietest stretches %.3g",
                  contradicted.empty() ? "" : ", ", column.c_str(), noise.sigma, SiUnit(column),
                  logged);
    contradicted += item;
  }
  std::string note;
  if (!estimated.empty()) note = "noise not declared, estimated from the logs: " + estimated;
  if (!contradicted.empty()) {
    note += (note.empty() ? "" : "; ") + std::string("declared noise below what the logs show: ") +
            contradicted + " (the fits and the verdict weigh by the declared)";
  }
  return note;
}

}  // namespace pneumaid
