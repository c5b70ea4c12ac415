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

// Intervals this many times the median or longer are rows lost (one lost row
// makes one of twice the median), not the clock's spread.
inline constexpr double kLostRowIntervals = 1.5;

// Whether `t` is a clock that does not keep time: its intervals shorter than
// kLostRowIntervals times the median (those of no lost row) spread beyond
// kStampJitter of the median. A logger whose loop does not keep time; it may
// also lose rows. The friction fit replays such a log from sample to sample
// as logged (a lost row an interval twice as long; gaps marked, SamplingGaps).
// A uniform clock that lost rows is read on that clock (ResampledUniformly):
// replayed at its logged times instead, a 1 kHz log with 2 % of its rows lost
// gave the negative vs 0.0079 +- 0.00035 for 0.01, where the uniform clock
// gave 0.0089 +- 0.0011 and the complete log 0.0089 +- 0.0011 (session 51,
// not understood); a jittery clock that lost 1 % of its rows, read on the
// uniform clock, took the negative vs 41 % low over 10 units, 5 of them out
// of tolerance.
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
