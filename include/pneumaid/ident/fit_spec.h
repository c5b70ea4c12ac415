// What a refinement fits: free parameters with bounds and scales, residual
// channels with their noise, the experiments fitted and held out, multistart.
// Read from `pneumaid-fit/1` YAML (docs/refinement.md; configs/fit-*.yaml).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace pneumaid {

inline constexpr const char* kFitSpecFormat = "pneumaid-fit/1";

enum class ParameterScale {
  kLinear,  // the solver steps in p / |p_start|
  kLog,     // the solver steps in ln p (for rates and positive gains)
};

struct FreeParameter {
  std::string path;  // params-v1 dotted path, e.g. "friction.positive.Fs"
  double lower = 0;  // bounds in the parameter's SI unit
  double upper = 0;
  ParameterScale scale = ParameterScale::kLinear;
};

struct ChannelWeight {
  // Noise standard deviation [SI]; 0: the manifest's declared sensor sigma.
  double sigma = 0;
  // Extra factor on the channel's weighted residuals.
  double weight = 1;
};

struct FitSpec {
  std::vector<FreeParameter> parameters;
  // Residual channels (x, p1, p2, q1, q2); a channel a log lacks is skipped.
  std::map<std::string, ChannelWeight> channels;
  // Experiments by id or by kind ("stroke", "validation").
  std::vector<std::string> fit = {"stroke"};
  std::vector<std::string> hold_out = {"validation"};
  // Extra starting points from a Latin hypercube inside the bounds (0: only
  // the given start).
  int multistart = 0;
  // Optional: refine in stages, each from the previous one's result, freeing
  // the listed parameters (an empty list: all of them). Output error from a
  // poor start has narrow basins in the parameters that set the timing (the
  // valve gain, the tube lag); fitting those first widens them.
  std::vector<std::vector<std::string>> stages;
  std::uint64_t seed = 1;
  int max_iterations = 50;
  std::string source;  // the file it came from, for messages and provenance
};

// Reads a fit spec; InputError (file, line, what was expected) for anything
// malformed, unknown keys and unknown parameter paths included.
FitSpec LoadFitSpec(const std::string& path);
FitSpec ParseFitSpec(const std::string& text, const std::string& source);

}  // namespace pneumaid
