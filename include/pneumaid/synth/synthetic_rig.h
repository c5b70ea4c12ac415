// The synthetic rig: runs a test protocol on a truth parameter set and
// produces the unit directory a real rig would log, instruments included
// (sample rate, noise, ADC quantisation, flow-meter lag) and written in rig
// units (mm, bar gauge, l/min). Hidden effects in the truth's `effects` act
// on the data without being declared anywhere.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "pneumaid/io/protocol.h"
#include "pneumaid/io/rig_writer.h"
#include "pneumaid/model/parameters.h"

namespace pneumaid {

struct SyntheticUnit {
  Manifest manifest;
  std::vector<RigLog> logs;
  Parameters truth;  // written as truth.yaml beside the logs, for tests only
};

// Deterministic for a given seed. Throws InputError when the truth cannot be
// simulated (invalid parameters, an effect the simulator refuses) and
// std::runtime_error when the simulator fails numerically.
SyntheticUnit Synthesize(const Parameters& truth, const Protocol& protocol, std::uint64_t seed,
                         const std::string& unit_id);

// unit.yaml, the logs and truth.yaml, as file name -> contents.
std::map<std::string, std::string> UnitFiles(const SyntheticUnit& unit);

// Manufacturing spread: each parameter whose path matches a pattern ('*'
// matches one path segment, e.g. "valve.*.q_max") is multiplied by
// 1 + U(-fraction, fraction), drawn from `seed`.
Parameters ApplySpread(const Parameters& params, const std::map<std::string, double>& fractions,
                       std::uint64_t seed);

// Multiplies each named parameter (an exact path) by its factor: an outlier
// unit. InputError for a path that names no parameter of `params`.
Parameters ApplyScale(const Parameters& params, const std::map<std::string, double>& factors);

// The sensor model on one sampled SI signal: first-order lag (exact for a
// signal held between samples), Gaussian noise, then ADC quantisation.
// With a null rng_state only the lag is applied.
std::vector<double> MeasureSignal(const std::vector<double>& si, double sample_period_s,
                                  const SensorModel& sensor, std::uint64_t* rng_state);

}  // namespace pneumaid
