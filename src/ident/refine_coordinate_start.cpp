#include "refine_coordinate_start.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "pneumaid/model/parameter_table.h"
#include "refine_friction_screen.h"
#include "refine_parameters.h"
#include "refine_verdict.h"

namespace pneumaid::refine_internal {
namespace {

// Grid points on each side of the current value: a factor span^(1/8)
// apart (1.052 for span 1.5), finer than the basins (docs/refinement.md).
constexpr int kStepsPerSide = 8;

struct Coordinate {
  std::string path;       // friction.<direction>.<name>
  std::string direction;  // "friction.positive." or "friction.negative."
  std::string name;       // Fs, Fd, b or vs
};

// The free friction coefficients of `spec` that the search moves.
std::vector<Coordinate> FreeFrictionCoordinates(const FitSpec& spec) {
  std::vector<Coordinate> out;
  for (const FreeParameter& p : spec.parameters) {
    for (const char* direction : {"friction.positive.", "friction.negative."}) {
      const std::string prefix = direction;
      if (p.path.rfind(prefix, 0) != 0) continue;
      const std::string name = p.path.substr(prefix.size());
      if (name == "Fs" || name == "Fd" || name == "b" || name == "vs")
        out.push_back({p.path, prefix, name});
    }
  }
  return out;
}

// Where a grid around a value near 0 is centred instead.
double Floor(const Coordinate& c, const Parameters& p) {
  if (c.name == "Fd") {
    double fs = 0;
    GetParameter(p, c.direction + "Fs", &fs);
    return 0.05 * fs;
  }
  if (c.name == "b") return 0.5;
  if (c.name == "vs") return 1e-3;
  return 0.1;  // Fs
}

}  // namespace

CoordinateSearch SearchFrictionCoordinates(const Parameters& start, const Unit& unit,
                                           const FitSpec& spec, const RefineOptions& options) {
  CoordinateSearch out;
  out.start = start;
  const auto score = [&](const Parameters& p) {
    ++out.candidates;
    return VerdictMeasure(p, unit, spec, options);
  };
  out.chi_square_before = out.chi_square_after = score(start);
  const std::vector<Coordinate> coordinates = FreeFrictionCoordinates(spec);
  std::string moves;
  for (int round = 0; round < options.coordinate_rounds; ++round) {
    double best = out.chi_square_after;
    Parameters best_params;
    const Coordinate* moved = nullptr;
    double from = 0, to = 0;
    for (const Coordinate& c : coordinates) {
      const FreeParameter* free = spec.FindParameter(c.path);
      double value = 0, fs = 0;
      GetParameter(out.start, c.path, &value);
      GetParameter(out.start, c.direction + "Fs", &fs);
      double fd = 0;
      GetParameter(out.start, c.direction + "Fd", &fd);
      const double centre = std::max(value, Floor(c, out.start));
      double previous = value;
      for (int i = -kStepsPerSide; i <= kStepsPerSide; ++i) {
        if (i == 0) continue;
        const double candidate = std::clamp(
            centre * std::pow(options.coordinate_span, static_cast<double>(i) / kStepsPerSide),
            free->lower, free->upper);
        if (candidate == value || candidate == previous) continue;
        previous = candidate;
        if ((c.name == "Fd" && candidate > fs) || (c.name == "Fs" && fd > candidate)) continue;
        Parameters p = out.start;
        SetParameter(&p, c.path, candidate);
        const double chi = score(p);
        if (chi < best) {
          best = chi;
          best_params = std::move(p);
          moved = &c;
          from = value;
          to = candidate;
        }
      }
    }
    if (moved == nullptr) break;
    out.start = std::move(best_params);
    out.chi_square_after = best;
    char move[160];
    std::snprintf(move, sizeof(move), "%s%s %.4g -> %.4g", moves.empty() ? "" : ", ",
                  moved->path.c_str(), from, to);
    moves += move;
  }
  out.moved = out.chi_square_after < out.chi_square_before;
  char line[200];
  if (!out.moved) {
    std::snprintf(line, sizeof(line),
                  "friction start one coefficient at a time: no move lowers the median reduced "
                  "chi-square %.3g (%d candidates simulated)",
                  out.chi_square_before, out.candidates);
    out.report = line;
    return out;
  }
  ForgetMoved(start, spec, &out.start);
  std::snprintf(line, sizeof(line),
                "friction start one coefficient at a time: median reduced chi-square %.3g -> "
                "%.3g (%d candidates simulated; ",
                out.chi_square_before, out.chi_square_after, out.candidates);
  out.report = line + moves + ")";
  return out;
}

std::vector<VelocityStart> StribeckVelocityStarts(const Parameters& from, const FitSpec& spec,
                                                  double divisor) {
  std::vector<VelocityStart> out;
  if (!(divisor > 1)) return out;
  for (const char* direction : {"positive", "negative"}) {
    const std::string path = std::string("friction.") + direction + ".vs";
    const FreeParameter* free = spec.FindParameter(path);
    double vs = 0;
    if (free == nullptr || !GetParameter(from, path, &vs)) continue;
    const double moved = std::clamp(vs / divisor, free->lower, free->upper);
    if (moved == vs) continue;
    Parameters start = from;
    SetParameter(&start, path, moved);
    ForgetMoved(from, spec, &start);
    out.push_back({direction, std::move(start)});
  }
  return out;
}

}  // namespace pneumaid::refine_internal
