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
// friction fit's uniform clock leaves unmeasured and validation cuts a run at.
std::vector<std::size_t> SamplingGaps(const std::vector<double>& t,
                                      double* median_interval_s = nullptr);

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
