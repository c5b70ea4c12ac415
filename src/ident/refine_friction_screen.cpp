#include "refine_friction_screen.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "friction_segments.h"
#include "friction_starts.h"
#include "pneumaid/model/parameter_table.h"
#include "refine_verdict.h"

namespace pneumaid::refine_internal {
namespace {

using friction_internal::FitSliding;

bool IsFree(const FitSpec& spec, const std::string& path) {
  return spec.FindParameter(path) != nullptr;
}

// `value` inside the spec's bounds of `path` (unchanged when not free).
double Bounded(const FitSpec& spec, const std::string& path, double value) {
  const FreeParameter* p = spec.FindParameter(path);
  return p == nullptr ? value : std::clamp(value, p->lower, p->upper);
}

}  // namespace

FrictionScreen ScreenFrictionStarts(const Parameters& start, const Unit& unit, const FitSpec& spec,
                                    const RefineOptions& options, bool even_if_explained,
                                    int alternatives) {
  FrictionScreen out;
  out.start = start;
  const auto score = [&](const Parameters& p) {
    ++out.candidates;
    const double chi = MedianRunChiSquare(WholeRunMisfits(p, unit, spec, options));
    return std::isnan(chi) ? HUGE_VAL : chi;
  };
  out.chi_square_before = out.chi_square_after = score(start);
  if (out.chi_square_before <= options.acceptable_reduced_chi_square && !even_if_explained)
    return out;
  // The force balance of the fitted runs' smooth slides.
  FrictionFitOptions friction;
  friction.force_balance = true;
  const double sigma_m = unit.manifest.DeclaredSigma("x", 1e-5);
  friction_internal::StrokeSelection selection;
  for (const Experiment* e : Select(unit, spec.fit, spec, false))
    selection.runs.push_back(e->entry.id);
  selection.slides_under_segments = true;  // nothing here replays the segments
  const friction_internal::StrokeData data = friction_internal::PrepareStrokes(
      unit, friction, friction_internal::StuckBand(friction, sigma_m), sigma_m, selection);
  Parameters& best = out.start;
  double& best_chi = out.chi_square_after;
  // `best` with a direction's Fs and vs at (fs, vs), its Fd and b from its
  // slides (where they are free and the slides enough).
  const auto candidate = [&](const std::string& prefix, int direction, double fs, double vs) {
    Parameters p = best;
    fs = Bounded(spec, prefix + "Fs", fs);
    vs = Bounded(spec, prefix + "vs", vs);
    SetParameter(&p, prefix + "Fs", fs);
    SetParameter(&p, prefix + "vs", vs);
    double fd = 0, b = 0;
    const bool sliding = IsFree(spec, prefix + "Fd") && IsFree(spec, prefix + "b");
    if (sliding && FitSliding(data.clusters, direction, fs, vs, &fd, &b) < HUGE_VAL) {
      SetParameter(&p, prefix + "Fd", Bounded(spec, prefix + "Fd", fd));
      SetParameter(&p, prefix + "b", Bounded(spec, prefix + "b", b));
    } else {
      GetParameter(p, prefix + "Fd", &fd);
      SetParameter(&p, prefix + "Fd", std::min(fd, fs));
    }
    return p;
  };
  // Every candidate simulated, with its median (for the alternatives).
  std::vector<std::pair<double, Parameters>> simulated;
  // Simulates (fs, vs) for a direction; keeps it when it is the best yet.
  const auto try_point = [&](const std::string& prefix, int direction, double fs, double vs) {
    Parameters p = candidate(prefix, direction, fs, vs);
    const double chi = score(p);
    if (alternatives > 0 && std::isfinite(chi)) simulated.emplace_back(chi, p);
    if (chi < best_chi) best_chi = chi, best = std::move(p);
  };
  struct Direction {
    std::string prefix;
    int sign;
  };
  std::vector<Direction> directions;
  for (const int sign : {+1, -1}) {
    const std::string prefix = std::string("friction.") + (sign > 0 ? "positive." : "negative.");
    if (IsFree(spec, prefix + "Fs") && IsFree(spec, prefix + "vs"))
      directions.push_back({prefix, sign});
  }
  const auto at = [&](const Direction& d, double* fs, double* vs) {
    GetParameter(best, d.prefix + "Fs", fs);
    GetParameter(best, d.prefix + "vs", vs);
  };
  // First each direction's Fd and b from its slides at the start's Fs and
  // vs, one direction, then the other (kept where the median drops): a
  // direction searched below is then judged with the other's sliding
  // friction as the slides tell it (the component fit's can be far off where
  // the force balance is not: Fd 0 and b 19.5 for 0.27 and 13.6).
  for (const Direction& d : directions) {
    double fs = 0, vs = 0;
    at(d, &fs, &vs);
    try_point(d.prefix, d.sign, fs, vs);
  }
  // Coarse, per direction: Fs over the fleet's range and beyond (1 to 32 N,
  // factors of 2^(1/4): a basin can be narrower than sqrt 2) at the
  // current vs brought into the vs grid's range (at vs 1 m/s the Stribeck
  // curve is flat and Fs only the sliding force), then vs (1 to 32 mm/s,
  // factors of 2) at the best Fs.
  for (const Direction& d : directions) {
    double fs = 0, vs = 0;
    at(d, &fs, &vs);
    vs = std::clamp(vs, 1e-3, 32e-3);
    for (int g = 0; g <= 20; ++g) try_point(d.prefix, d.sign, std::pow(2.0, 0.25 * g), vs);
    at(d, &fs, &vs);
    for (int g = 0; g <= 5; ++g) try_point(d.prefix, d.sign, fs, 1e-3 * std::pow(2.0, g));
  }
  // Fine: a pattern search over every direction's Fs and vs with shrinking
  // factors (the basins are narrow: a factor 1.2 in Fs can be the
  // difference), each factor repeated while it gains; vs moves by the
  // factor squared, Fd and b follow from the slides.
  for (const double factor : {1.41, 1.19, 1.09, 1.04}) {
    for (int repeat = 0; repeat < 2; ++repeat) {
      const double before = best_chi;
      for (const Direction& d : directions) {
        for (const double f : {factor, 1 / factor}) {
          double fs = 0, vs = 0;
          at(d, &fs, &vs);
          try_point(d.prefix, d.sign, fs * f, vs);
          at(d, &fs, &vs);
          try_point(d.prefix, d.sign, fs, vs * f * f);
        }
      }
      if (!(best_chi < before)) break;
    }
  }
  // The next-best candidates that differ from those already taken.
  std::stable_sort(simulated.begin(), simulated.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  const auto distinct = [&](const Parameters& a, const Parameters& b) {
    for (const Direction& d : directions) {
      double fa = 0, fb = 0, va = 0, vb = 0;
      GetParameter(a, d.prefix + "Fs", &fa);
      GetParameter(b, d.prefix + "Fs", &fb);
      GetParameter(a, d.prefix + "vs", &va);
      GetParameter(b, d.prefix + "vs", &vb);
      const auto ratio = [](double x, double y) {
        return std::max(x, y) / std::max(std::min(x, y), 1e-12);
      };
      if (ratio(fa, fb) > kDistinctStatic || ratio(va, vb) > kDistinctStribeck) return true;
    }
    return false;
  };
  for (auto& [chi, p] : simulated) {
    if (static_cast<int>(out.alternatives.size()) >= alternatives) break;
    bool fresh = distinct(p, best) && distinct(p, start);
    for (const Parameters& taken : out.alternatives) fresh = fresh && distinct(p, taken);
    if (fresh) out.alternatives.push_back(std::move(p));
  }
  // A moved coefficient's standard error was the component fit's.
  const auto forget_moved = [&](Parameters* p) {
    for (const FreeParameter& free : spec.parameters) {
      double before = 0, after = 0;
      if (GetParameter(start, free.path, &before) && GetParameter(*p, free.path, &after) &&
          before != after) {
        p->uncertainty.erase(free.path);
      }
    }
  };
  forget_moved(&best);
  for (Parameters& alternative : out.alternatives) forget_moved(&alternative);
  if (best_chi < out.chi_square_before) {
    char line[200];
    std::snprintf(line, sizeof(line),
                  "friction start read off the logs: median reduced chi-square %.3g -> %.3g "
                  "(%d candidates simulated)",
                  out.chi_square_before, best_chi, out.candidates);
    out.report = line;
  }
  return out;
}

}  // namespace pneumaid::refine_internal
