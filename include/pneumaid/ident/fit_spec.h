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
  int line = 0;  // the spec file's line that frees it (0: built in code)
};

struct ChannelWeight {
  // Noise standard deviation [SI]; 0: the manifest's declared sensor sigma.
  double sigma = 0;
  // Extra factor on the channel's weighted residuals.
  double weight = 1;
};

struct FitStage {
  // Parameters freed in this stage (paths under `parameters`); empty: all.
  std::vector<std::string> parameters;
  // Multiple shooting: cut every fitted run where the rod arrived at rest in
  // a stuck phase (as FrictionFitOptions' defaults read them) and simulate
  // each window from its logged state there (the phase's median x, p1, p2,
  // v = 0, the tube's lag replayed from the command). Errors cannot accumulate from window to
  // window, which widens the basin around the optimum; a later full-horizon
  // stage then fits the runs as the simulator replays them.
  bool windows = false;
  // Instead of a simulation fit: refit the Stribeck friction of both
  // directions by the rod replay driven by the measured pressures (the
  // identification's friction fit, docs/identification.md) on the unit's
  // stroke logs. It needs no start near the optimum and no simulation, so it
  // puts friction in the basin before the simulation stages.
  bool friction_replay = false;
};

struct FitSpec {
  std::vector<FreeParameter> parameters;
  // Residual channels (x, p1, p2, q1, q2); a channel a log lacks is skipped.
  std::map<std::string, ChannelWeight> channels;
  // Experiments by id or by kind ("stroke", "validation").
  std::vector<std::string> fit = {"stroke"};
  std::vector<std::string> hold_out = {"validation"};
  // The spec file's line of each entry of `fit` and `hold_out`, for messages
  // about a unit that lacks one or a run both lists name (empty: built in code).
  std::map<std::string, int> fit_lines, hold_out_lines;
  // Extra starting points from a Latin hypercube inside the bounds (0: only
  // the given start).
  int multistart = 0;
  // Optional: refine in stages, each from the previous one's result. Output
  // error from a poor start has narrow basins in the parameters that set the
  // timing (the valve gain, the tube lag); fitting those first, or fitting
  // windows first, widens them.
  std::vector<FitStage> stages;
  // Estimate each fitted run's (and window's) initial chamber pressures as
  // nuisance parameters, each tied to its logged value by a prior of the
  // logged value's standard error (`initial_pressures: fit`, the default),
  // or start from the logged values (`logged`). Stick-slip amplifies a start
  // a few tens of Pa off into a misfit that the model's parameters would
  // otherwise absorb (docs/refinement.md).
  bool fit_initial_pressures = true;
  std::uint64_t seed = 1;
  int max_iterations = 50;
  std::string source;  // the file it came from, for messages and provenance

  // Checks a spec however it was made (read from YAML or built in code):
  // known parameter paths, each once, bounds inside the parameter's physical
  // range with min < max (min > 0 on a log scale), no more free parameters
  // than the sensitivities hold, known channels with sigma >= 0 and weight
  // > 0, something to fit, stages naming free parameters only and ending in
  // a simulation stage, multistart 0..1000, max_iterations >= 1. On failure
  // `error` names the field. Refine() calls it.
  bool IsValid(std::string* error) const;

  // What messages call the spec: its file, or "fit spec" for one built in code.
  std::string Name() const { return source.empty() ? "fit spec" : source; }

  // The free parameter at `path`, or nullptr when the spec holds it fixed.
  const FreeParameter* FindParameter(const std::string& path) const;
};

// Reads a fit spec; InputError (file, line, what was expected) for anything
// malformed, unknown keys and unknown parameter paths included.
FitSpec LoadFitSpec(const std::string& path);
FitSpec ParseFitSpec(const std::string& text, const std::string& source);

}  // namespace pneumaid
