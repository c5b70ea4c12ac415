#include "pneumaid/io/log_notes.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "../util/median.h"

using pneumaid::internal::Median;

namespace pneumaid {
namespace {

constexpr const char* kGaugeHint =
    " (a gauge unit where the supply is absolute, or the other way?)";

template <typename... Numbers>
std::string Format(const char* format, Numbers... numbers) {
  char text[256];
  std::snprintf(text, sizeof(text), format, numbers...);
  return text;
}

// `t` counts from the log's first sample; the note shows the log's own time.
std::string SamplingGapNote(const std::vector<double>& t, double time_origin_s) {
  double median = 0;
  const std::vector<std::size_t> gaps = SamplingGaps(t, &median);
  if (gaps.empty()) return {};
  std::size_t longest = gaps.front();
  for (std::size_t i : gaps) {
    if (t[i + 1] - t[i] > t[longest + 1] - t[longest]) longest = i;
  }
  const double interval = t[longest + 1] - t[longest];
  const double missing = std::round(interval / median) - 1;
  return std::to_string(gaps.size()) + (gaps.size() == 1 ? " gap" : " gaps") +
         Format(
             " in the sampling (intervals over %.3g times the median %.3g ms), the longest "
             "%.4g ms after t = %.8g s, about %.0f samples missing",
             kSamplingGapIntervals, median * 1e3, interval * 1e3, t[longest] + time_origin_s,
             missing);
}

}  // namespace

double MedianInterval(const std::vector<double>& t) {
  if (t.size() < 2) return 0;
  std::vector<double> intervals(t.size() - 1);
  for (std::size_t i = 1; i < t.size(); ++i) intervals[i - 1] = t[i] - t[i - 1];
  return Median(std::move(intervals));
}

double UniformPeriod(const std::vector<double>& t) {
  if (t.size() < 2) return 0;
  const double period = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
  if (!(period > 0)) return 0;
  for (std::size_t i = 1; i < t.size(); ++i) {
    const double grid = t.front() + static_cast<double>(i) * period;
    if (std::fabs(t[i] - grid) > kStampJitter * period) return 0;
  }
  return period;
}

bool IrregularClock(const std::vector<double>& t) {
  if (t.size() < 3 || UniformPeriod(t) > 0) return false;
  const double median = MedianInterval(t);
  if (!(median > 0)) return false;
  // Each stamp's place on a grid that lost rows: the whole intervals so far.
  std::vector<double> place(t.size(), 0.0);
  for (std::size_t i = 1; i < t.size(); ++i)
    place[i] = place[i - 1] + std::max(1.0, std::round((t[i] - t[i - 1]) / median));
  const double period = (t.back() - t.front()) / place.back();
  for (std::size_t i = 1; i < t.size(); ++i) {
    if (std::fabs(t[i] - t.front() - place[i] * period) > kStampJitter * period) return true;
  }
  return false;
}

std::vector<std::size_t> SamplingGaps(const std::vector<double>& t, double* median_interval_s) {
  if (median_interval_s != nullptr) *median_interval_s = 0;
  if (t.size() < 3) return {};
  const double median = MedianInterval(t);
  if (median_interval_s != nullptr) *median_interval_s = median;
  std::vector<std::size_t> gaps;
  if (!(median > 0)) return gaps;
  for (std::size_t i = 0; i + 1 < t.size(); ++i) {
    if (t[i + 1] - t[i] > kSamplingGapIntervals * median) gaps.push_back(i);
  }
  return gaps;
}

std::vector<std::string> LogNotes(const Experiment& experiment) {
  std::vector<std::string> notes;
  const std::string gaps = SamplingGapNote(experiment.column("t"), experiment.time_origin_s);
  if (!gaps.empty()) notes.push_back(gaps);
  if (experiment.unterminated_last_row) {
    notes.push_back(
        "the last row has no line end: a log cut while it was written ends so, and its last "
        "number may be cut short");
  }
  return notes;
}

std::vector<std::string> ManifestNotes(const Unit& unit) {
  std::vector<std::string> notes;
  const double supply_Pa = unit.manifest.rig.supply_pressure_Pa;
  for (const Experiment& e : unit.experiments) {
    const auto& p_up = e.column("p_up");
    if (!p_up.empty()) {
      const double median_Pa = Median(p_up);
      if (std::abs(median_Pa - supply_Pa) > kSupplyMismatchFraction * supply_Pa) {
        const char* side = median_Pa < supply_Pa ? "below" : "above";
        notes.push_back("valve log '" + e.entry.id + "'" +
                        Format(": p_up's median %.4g bar abs is %.0f %% ", median_Pa / 1e5,
                               std::abs(median_Pa / supply_Pa - 1) * 100) +
                        side + Format(" the rig's supply_pressure %.4g bar abs", supply_Pa / 1e5) +
                        kGaugeHint);
      }
    }
    // A log listed twice is fitted twice, and a validation run that is also
    // a fitted one is not held out (the format is silent on it).
    for (const Experiment& earlier : unit.experiments) {
      if (&earlier == &e) break;
      if (earlier.sha256.empty() || earlier.sha256 != e.sha256) continue;
      notes.push_back("logs '" + earlier.entry.id + "' (" + ToString(earlier.entry.kind) +
                      ") and '" + e.entry.id + "' (" + ToString(e.entry.kind) +
                      ") are the same bytes: a run listed twice counts twice in a fit, and a "
                      "held-out run that is also fitted is not held out");
      break;
    }
    const auto& p1 = e.column("p1");
    const auto& p2 = e.column("p2");
    if (p1.empty() || p1.size() != p2.size()) continue;
    // The higher chamber's pressure that 1 % of the log exceeds: a chamber
    // compressed by a stopping rod passes the supply for a moment (29 % on
    // a worn seal's strokes), a supply written wrong is passed at every hold.
    std::vector<double> higher(p1.size());
    for (std::size_t i = 0; i < p1.size(); ++i) higher[i] = std::max(p1[i], p2[i]);
    const std::size_t at = higher.size() - 1 - higher.size() / 100;
    std::nth_element(higher.begin(), higher.begin() + at, higher.end());
    const double high_Pa = higher[at];
    if (high_Pa > (1 + kSupplyMismatchFraction) * supply_Pa) {
      notes.push_back("log '" + e.entry.id + "'" +
                      Format(": the higher chamber pressure exceeds %.4g bar abs for 1 %% of "
                             "the log, %.0f %% above the rig's supply_pressure %.4g bar abs",
                             high_Pa / 1e5, (high_Pa / supply_Pa - 1) * 100, supply_Pa / 1e5) +
                      kGaugeHint);
    }
  }
  return notes;
}

}  // namespace pneumaid
