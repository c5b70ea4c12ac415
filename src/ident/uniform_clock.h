// Logs on a uniform clock: the friction fit's replay steps sample by sample,
// so a stroke log that a lossy logger thinned (or stamped with jitter) is
// read on a uniform clock instead.
#pragma once

#include <memory>
#include <vector>

#include "pneumaid/io/rig_data.h"

namespace pneumaid::internal {

// The sampling interval of `t` when every interval is within 1 % of the
// mean, else 0.
double UniformPeriod(const std::vector<double>& t);

// `e` on a uniform clock at its median sampling interval (MedianInterval): each column
// interpolated linearly between its samples, the command (`u`) held from
// each sample. `in_gap`, when given, marks the clock's samples that lie
// inside a gap of the log (an interval over kSamplingGapIntervals times the
// median, the rule `check` notes): interpolated across rows the logger lost,
// they are no measurement.
std::shared_ptr<const Experiment> ResampledUniformly(const Experiment& e,
                                                     std::vector<bool>* in_gap = nullptr);

}  // namespace pneumaid::internal
