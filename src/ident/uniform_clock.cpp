#include "uniform_clock.h"

#include <algorithm>
#include <cmath>

#include "pneumaid/io/log_notes.h"

namespace pneumaid::internal {

std::shared_ptr<const Experiment> ResampledUniformly(const Experiment& e,
                                                     std::vector<bool>* in_gap) {
  const auto& t = e.column("t");
  auto out = std::make_shared<Experiment>();
  out->entry = e.entry;
  out->path = e.path;
  out->sha256 = e.sha256;
  out->time_origin_s = e.time_origin_s;
  if (t.size() < 2) return out;
  const double period = MedianInterval(t);
  const auto samples =
      static_cast<std::size_t>(std::floor((t.back() - t.front()) / period + 1e-9)) + 1;
  std::vector<double> clock(samples);
  for (std::size_t k = 0; k < samples; ++k) clock[k] = t.front() + static_cast<double>(k) * period;
  // The logged interval each clock sample lies in: t[left[k]] <= clock[k] <
  // t[left[k] + 1] (the last interval for the last sample).
  std::vector<std::size_t> left(samples);
  for (std::size_t k = 0, j = 0; k < samples; ++k) {
    while (j + 2 < t.size() && t[j + 1] <= clock[k]) ++j;
    left[k] = j;
  }
  if (in_gap != nullptr) {
    std::vector<bool> gap(t.size() - 1, false);  // per logged interval
    for (std::size_t j : SamplingGaps(t)) gap[j] = true;
    in_gap->assign(samples, false);
    const double round_off_s = 1e-9 * period;
    for (std::size_t k = 0; k < samples; ++k) {
      const std::size_t j = left[k];
      (*in_gap)[k] = gap[j] && clock[k] > t[j] + round_off_s && clock[k] < t[j + 1] - round_off_s;
    }
  }
  for (const auto& [name, values] : e.columns) {
    std::vector<double>& column = out->columns[name];
    if (name == "t") {
      column = clock;
      continue;
    }
    column.resize(samples);
    for (std::size_t k = 0; k < samples; ++k) {
      const std::size_t j = left[k];
      const double w = std::clamp((clock[k] - t[j]) / (t[j + 1] - t[j]), 0.0, 1.0);
      column[k] = name == "u" ? (w < 1 ? values[j] : values[j + 1])
                              : (1 - w) * values[j] + w * values[j + 1];
    }
  }
  return out;
}

}  // namespace pneumaid::internal
