// Diagnose (diagnose.h), "where": the residuals of simulated runs per channel
// and regime, the worst windows, and the per-channel mean squares the
// decision rule compares.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "pneumaid/diagnose/diagnose.h"

namespace pneumaid::diagnose_internal {

// The regimes a sample can be in (several at once), as bits.
enum Regime : unsigned {
  kAllSamples = 1u << 0,
  kExtendCommand = 1u << 1,   // u > 0: chamber 1 charging, chamber 2 exhausting
  kRetractCommand = 1u << 2,  // u < 0: chamber 2 charging, chamber 1 exhausting
  kValvesShut = 1u << 3,      // |u| below the shut threshold, settled
  kSmallOpening = 1u << 4,    // 0 < |u| < 0.3 V
  kAfterChange = 1u << 5,     // the first after_change_s after a command change
  kSliding = 1u << 6,
  kStuck = 1u << 7,      // the logged rod at rest away from the ends
  kAtEndStop = 1u << 8,  // within 0.5 mm of an end of the stroke
};
inline constexpr int kRegimeCount = 9;
const char* RegimeName(int bit_index);

// Sums of squares and counts per channel, over some runs.
struct ChannelSums {
  std::map<std::string, double> squares;
  std::map<std::string, long> samples;
  double MeanSquare(const std::string& channel) const;
  void Add(const ChannelSums& other);
};

// Per run of a validation report: its channels' sums (the runs with a failed
// simulation count as infinitely far).
std::map<std::string, ChannelSums> RunSums(const ValidationReport& report);

// The sums of `runs` pooled.
ChannelSums Pool(const std::map<std::string, ChannelSums>& per_run,
                 const std::vector<std::string>& runs);

// Sum over channels of the mean square in units of `scale` (per channel
// variance): the cost the decision rule compares. Channels without a scale
// are left out.
double NormalisedCost(const ChannelSums& sums, const std::map<std::string, double>& scale);

// "Where" for one model: residuals per channel and regime, the worst windows.
DiscrepancyMap MapDiscrepancy(const ValidationReport& report, const Unit& unit,
                              double half_stroke_m, const DiagnoseOptions& options);

}  // namespace pneumaid::diagnose_internal
