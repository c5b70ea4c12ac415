// Logs on a uniform clock: the friction fit's replay steps sample by sample,
// so a stroke log that a lossy logger thinned (or stamped with jitter) is
// read on a uniform clock instead.
#pragma once

#include <memory>
#include <vector>

#include "pneumaid/io/rig_data.h"

namespace pneumaid::internal {

// How far a time stamp may lie from the uniform grid through a log's first
// and last ones [intervals] for the log to be read as sampled on that grid:
// a logger's clock stamps with jitter, and a log whose stamps jitter by 1 %
// of an interval, read on a clock at its median interval instead, took the
// columns' interpolation into the friction fit (a negative vs 16 to 37 % low
// at +-8 to 20 us on a 1 kHz log, session 50). A lost row moves the stamps
// by half an interval or more from that grid.
inline constexpr double kStampJitter = 0.1;

// The sampling interval of `t` (the mean) when every stamp lies within
// kStampJitter intervals of the uniform grid through the first and the last,
// else 0.
double UniformPeriod(const std::vector<double>& t);

// The longest interval of an irregular clock [median intervals]: a lost row
// makes one of twice the median, or more.
inline constexpr double kIrregularClockStretch = 1.5;

// Whether `t` (not on a uniform grid: UniformPeriod 0) is a clock whose
// intervals vary, none over kIrregularClockStretch times the median: a logger
// whose loop does not keep time. The friction fit replays such a log from
// sample to sample as logged. A log that lost rows it reads on a uniform
// clock instead (ResampledUniformly), gaps marked: replayed at its logged
// times, a 1 kHz log with 2 % of its rows lost gave the negative vs 0.0079 +-
// 0.00035 for 0.01, where the uniform clock gave 0.0089 +- 0.0011 and the
// complete log 0.0089 +- 0.0011 (session 51, not understood).
bool IrregularClock(const std::vector<double>& t);

// `e` on a uniform clock at its median sampling interval (MedianInterval): each column
// interpolated linearly between its samples, the command (`u`) held from
// each sample. `in_gap`, when given, marks the clock's samples that lie
// inside a gap of the log (an interval over kSamplingGapIntervals times the
// median, the rule `check` notes): interpolated across rows the logger lost,
// they are no measurement.
std::shared_ptr<const Experiment> ResampledUniformly(const Experiment& e,
                                                     std::vector<bool>* in_gap = nullptr);

}  // namespace pneumaid::internal
