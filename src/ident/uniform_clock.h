// Logs on a uniform clock: the friction fit replays a stroke log of a uniform
// clock that lost rows (a lossy logger: not UniformPeriod, not IrregularClock,
// log_notes.h) on that clock, the lost rows interpolated.
#pragma once

#include <memory>
#include <vector>

#include "pneumaid/io/log_notes.h"
#include "pneumaid/io/rig_data.h"

namespace pneumaid::internal {

// `e` on a uniform clock at its median sampling interval (MedianInterval): each column
// interpolated linearly between its samples, the command (`u`) held from
// each sample. `in_gap`, when given, marks the clock's samples that lie
// inside a gap of the log (an interval over kSamplingGapIntervals times the
// median, the rule `check` notes): interpolated across rows the logger lost,
// they are no measurement.
std::shared_ptr<const Experiment> ResampledUniformly(const Experiment& e,
                                                     std::vector<bool>* in_gap = nullptr);

}  // namespace pneumaid::internal
