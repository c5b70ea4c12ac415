// Refinement's friction screen, the searches that propose its candidates
// (friction_screen_search.h).
#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "friction_screen_search.h"

namespace pneumaid::refine_internal {

void FrictionScreenSearch::SlidingFromSlides() {
  for (const Direction& d : directions_) {
    double fs = 0, vs = 0;
    At(d, &fs, &vs);
    Try(d, fs, vs);
  }
}

void FrictionScreenSearch::CoarseGrid() {
  for (const Direction& d : directions_) {
    double fs = 0, vs = 0;
    At(d, &fs, &vs);
    vs = std::clamp(vs, 1e-3, 32e-3);
    for (int g = 0; g <= 20; ++g) Try(d, std::pow(2.0, 0.25 * g), vs);
    At(d, &fs, &vs);
    for (int g = 0; g <= 5; ++g) Try(d, fs, 1e-3 * std::pow(2.0, g));
  }
}

void FrictionScreenSearch::FullGrid() {
  for (const Direction& d : directions_) {
    const Parameters base = out_->start;  // each point from it: Fd <= Fs holds per point
    std::vector<Parameters> grid;
    for (int g = 0; g <= 20; ++g) {
      for (int h = 0; h <= 10; ++h)
        grid.push_back(Candidate(d, std::pow(2.0, 0.25 * g), 1e-3 * std::pow(2.0, 0.5 * h), &base));
    }
    ConsiderAll(std::move(grid));
  }
}

void FrictionScreenSearch::SlidingGrid() {
  for (const Direction& d : directions_) {
    if (!SlidingFree(d)) continue;
    const Parameters base = out_->start;
    double fs = 0, fd = 0, b = 0;
    GetParameter(base, d.prefix + "Fs", &fs);
    GetParameter(base, d.prefix + "Fd", &fd);
    GetParameter(base, d.prefix + "b", &b);
    fd = std::max(fd, 0.05 * fs);
    b = std::max(b, 1.0);
    std::vector<Parameters> grid;
    for (int i = -3; i <= 1; ++i) {
      for (int j = -2; j <= 2; ++j) {
        if (i == 0 && j == 0) continue;
        Parameters p = base;
        SetParameter(&p, d.prefix + "Fd",
                     Bounded(d.prefix + "Fd", std::min(fd * std::ldexp(1.0, i), fs)));
        SetParameter(&p, d.prefix + "b", Bounded(d.prefix + "b", b * std::ldexp(1.0, j)));
        grid.push_back(std::move(p));
      }
    }
    ConsiderAll(std::move(grid));
  }
}

void FrictionScreenSearch::JointGrid() {
  for (const Direction& d : directions_) {
    if (!SlidingFree(d)) continue;
    const Parameters base = out_->start;
    std::vector<Parameters> grid;
    for (int g = 0; g <= 10; ++g) {
      for (int h = 0; h <= 5; ++h) {
        const Parameters point =
            Candidate(d, std::pow(2.0, 0.5 * g), 1e-3 * std::ldexp(1.0, h), &base);
        double fs = 0;  // within the spec's bounds
        GetParameter(point, d.prefix + "Fs", &fs);
        for (const double share : {0.02, 0.1, 0.3, 0.6}) {
          for (const double b : {1.0, 2.5, 6.0, 15.0}) {
            Parameters p = point;
            SetParameter(&p, d.prefix + "Fd", Bounded(d.prefix + "Fd", share * fs));
            SetParameter(&p, d.prefix + "b", Bounded(d.prefix + "b", b));
            grid.push_back(std::move(p));
          }
        }
      }
    }
    ConsiderAll(std::move(grid));
  }
}

void FrictionScreenSearch::ProfiledGrid(const Parameters& start) {
  for (const Direction& d : directions_) {
    if (!SlidingFree(d)) continue;
    const Parameters base = out_->start;
    double centre = 0;
    GetParameter(start, d.prefix + "Fs", &centre);
    for (const double vs : {2e-3, 4e-3, 8e-3, 16e-3}) {
      for (const double share : {0.1, 0.3, 0.6}) {
        for (const double b : {2.5, 6.0, 15.0}) {
          int best_k = 0;
          double best = HUGE_VAL;
          const auto at = [&](int k) {
            Parameters p = Candidate(d, centre * (1 + 0.015 * k), vs, &base);
            double fs = 0;  // within the spec's bounds
            GetParameter(p, d.prefix + "Fs", &fs);
            SetParameter(&p, d.prefix + "Fd", std::min(Bounded(d.prefix + "Fd", share * fs), fs));
            SetParameter(&p, d.prefix + "b", Bounded(d.prefix + "b", b));
            return p;
          };
          // Ranked against the line's best so far (at least the search's).
          const auto bound = [&] { return std::max(best, out_->ranked_after); };
          std::vector<Parameters> line;
          for (int k = -10; k <= 10; k += 2) line.push_back(at(k));
          ConsiderAll(std::move(line), bound, [&](std::size_t i, double measure) {
            if (measure < best) best = measure, best_k = -10 + 2 * static_cast<int>(i);
          });
          std::vector<Parameters> neighbours;
          for (const int k : {best_k - 1, best_k + 1}) {
            if (std::abs(k) <= 10) neighbours.push_back(at(k));
          }
          ConsiderAll(std::move(neighbours), bound);
        }
      }
    }
  }
}

void FrictionScreenSearch::PatternSearch() {
  for (const double factor : {1.41, 1.19, 1.09, 1.04}) {
    for (int repeat = 0; repeat < 2; ++repeat) {
      const double before = out_->ranked_after;
      for (const Direction& d : directions_) {
        for (const double f : {factor, 1 / factor}) {
          double fs = 0, vs = 0;
          At(d, &fs, &vs);
          Try(d, fs * f, vs);
          At(d, &fs, &vs);
          Try(d, fs, vs * f * f);
          if (measure_ == ScreenMeasure::kWindows) {
            Scale(d, Sliding::kDynamic, f * f);
            Scale(d, Sliding::kViscous, f * f);
          }
        }
      }
      if (!(out_->ranked_after < before)) break;
    }
  }
}

void FrictionScreenSearch::Scale(const Direction& d, Sliding which, double f) {
  const bool dynamic = which == Sliding::kDynamic;
  const std::string path = d.prefix + (dynamic ? "Fd" : "b");
  if (!IsFree(spec_, path)) return;
  Parameters p = out_->start;
  double value = 0, fs = 0;
  GetParameter(p, path, &value);
  GetParameter(p, d.prefix + "Fs", &fs);
  const double scaled = Bounded(path, value * f);
  if (scaled == value || (dynamic && scaled > fs)) return;
  SetParameter(&p, path, scaled);
  Consider(std::move(p));
}

void FrictionScreenSearch::SearchByWindows(const Parameters& start) {
  FullGrid();
  SlidingGrid();
  PatternSearch();
  if (std::none_of(directions_.begin(), directions_.end(),
                   [this](const Direction& d) { return SlidingFree(d); }))
    return;
  Parameters pairwise = std::exchange(out_->start, start);  // the joint search from the start
  const double pairwise_ranked = std::exchange(out_->ranked_after, out_->ranked_before);
  Rebase();
  JointGrid();
  PatternSearch();
  if (pairwise_ranked < out_->ranked_after) {
    std::swap(pairwise, out_->start);  // the pairwise best first, the joint one second
    out_->ranked_after = pairwise_ranked;
  }
  runner_up_ = std::move(pairwise);
  if (!keep_simulated_) return;                         // no alternatives asked for
  Parameters best = std::exchange(out_->start, start);  // the profiled search from the start
  const double best_ranked = std::exchange(out_->ranked_after, out_->ranked_before);
  Rebase();
  profiling_ = true;  // its candidates are not ranked among the alternatives
  ProfiledGrid(start);
  PatternSearch();
  profiling_ = false;
  profiled_ = std::exchange(out_->start, std::move(best));
  out_->ranked_after = best_ranked;
  Rebase();
}

}  // namespace pneumaid::refine_internal
