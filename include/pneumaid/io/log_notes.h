// What `pneumaid check` says about a unit's logs beyond the format: things
// pneumaid-rig/1 allows but that are likely a mistake of the rig or its
// manifest, or that cost a fit accuracy. Notes for a person to read, never
// errors: a log that breaks the format is an InputError where it is read.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "pneumaid/io/rig_data.h"

namespace pneumaid {

// A sampling interval longer than this many times the log's median interval
// is a gap (rows lost by the logger): a dropped row or two (2 or 3 times) is
// common and harmless, a longer gap hides what the rod did while it lasted.
constexpr double kSamplingGapIntervals = 3.5;

// The median of t's intervals (0 with fewer than two samples).
double MedianInterval(const std::vector<double>& t);

// The sampling's gaps in `t`: the index i of each interval t[i + 1] - t[i]
// over kSamplingGapIntervals times the median interval, in order (none with
// fewer than three samples or a median of 0); the median in
// `median_interval_s` when given. The one rule that `check` notes, the
// friction fit leaves unmeasured and validation cuts a run at.
std::vector<std::size_t> SamplingGaps(const std::vector<double>& t,
                                      double* median_interval_s = nullptr);

// How far a time stamp may lie from a uniform grid [intervals] for the log
// to be read as sampled on that grid: a logger's clock stamps with jitter,
// and a log whose stamps jitter by 1 % of an interval, read on a clock at its
// median interval instead, took the columns' interpolation into the friction
// fit (a negative vs 16 to 37 % low at +-8 to 20 us on a 1 kHz log, session
// 50). A lost row moves the stamps by half an interval or more from the
// grid through the first and last.
inline constexpr double kStampJitter = 0.1;

// The sampling interval of `t` (the mean) when every stamp lies within
// kStampJitter intervals of the uniform grid through the first and the last,
// else 0.
double UniformPeriod(const std::vector<double>& t);

// Whether `t` is a clock that keeps no time: not on a uniform grid
// (UniformPeriod 0), nor on one that lost rows (each interval a whole number
// of the grid's, the stamps within kStampJitter of it). A logger loop on an
// operating system that does not keep its time; it may lose rows too. The
// friction fit replays such a log at its logged times; a uniform clock that
// lost rows it reads on that clock (src/ident/uniform_clock.h). Replayed at
// its logged times instead, a 1 kHz log with 2 % of its rows lost gave the
// negative vs 0.0079 +- 0.00035 for 0.01, where the uniform clock gave 0.0089
// +- 0.0011 and the complete log 0.0089 +- 0.0011 (session 51, not
// understood); a jittery clock that lost 1 % of its rows, read on the uniform
// clock, took the negative vs 41 % low over 10 units, 5 out of tolerance.
// A channel's noise estimate divides its differences by the logged times of
// any log not on a uniform grid (channel_noise.h).
bool IrregularClock(const std::vector<double>& t);

// A valve log's median p_up further than this fraction from the manifest's
// supply_pressure, or the higher chamber pressure above the supply by more
// than it for 1 % of a log (a stopping rod's compression passes the supply
// for a moment).
constexpr double kSupplyMismatchFraction = 0.1;

// The notes on one log: its sampling gaps ("3 gaps in the sampling, the
// longest 22 ms after t = 3.201 s, about 21 samples") and a last row with no
// line end (a log cut while it was written). Empty when there is nothing to
// say.
std::vector<std::string> LogNotes(const Experiment& experiment);

// The notes on a unit's manifest against its logs: a supply_pressure that the
// valve logs' p_up or the chamber pressures contradict (a gauge unit where
// the rig's supply is absolute, or the other way); two experiments whose logs
// are the same bytes.
std::vector<std::string> ManifestNotes(const Unit& unit);

}  // namespace pneumaid
