#include "refine_friction_screen.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iterator>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "friction_screen_search.h"
#include "friction_segments.h"
#include "friction_starts.h"
#include "pneumaid/model/parameter_table.h"
#include "pneumaid/validate/logged_run.h"
#include "ranked_candidates.h"
#include "refine_parameters.h"
#include "refine_verdict.h"
#include "windowed_measures.h"

namespace pneumaid::refine_internal {
using friction_internal::FitSliding;

void FrictionScreenSearch::ReadSlides() {
  FrictionFitOptions friction;
  friction.force_balance = true;
  friction_internal::StrokeSelection selection;
  for (const Experiment* e : Select(unit_, spec_, ExperimentList::kFit, false))
    selection.runs.push_back(e->entry.id);
  selection.slides_under_segments = true;  // nothing here replays the segments
  data_ = friction_internal::PrepareStrokes(unit_, friction, selection);
}

void FrictionScreenSearch::PickAlternatives(const Parameters& start, int count) {
  // Whether `p` differs from those fitted before it.
  const auto fresh = [&](const Parameters& p) {
    bool distinct = Distinct(p, out_->start) && Distinct(p, start);
    for (const Parameters& taken : out_->alternatives) distinct = distinct && Distinct(p, taken);
    return distinct;
  };
  // Takes `p` when there is room and it is fresh.
  const auto take = [&](Parameters& p) {
    if (static_cast<int>(out_->alternatives.size()) < count && fresh(p))
      out_->alternatives.push_back(std::move(p));
  };
  if (runner_up_) take(*runner_up_);
  if (profiled_) {
    ++count;  // one more slot: the profiled best where distinct, else the next by rank
    out_->profiled = *profiled_;
    const std::size_t before = out_->alternatives.size();
    take(*profiled_);
    if (out_->alternatives.size() > before) out_->profiled_alternative = static_cast<int>(before);
  }
  out_->runner_ups = static_cast<int>(out_->alternatives.size());
  // By rank (as if every candidate had been simulated whole).
  simulated_.TakeInOrder([&] { return static_cast<int>(out_->alternatives.size()) < count; }, fresh,
                         [this](const Parameters& p) { return Score(p); }, take);
}

Parameters FrictionScreenSearch::Candidate(const Direction& d, double fs, double vs,
                                           const Parameters* base) const {
  Parameters p = base != nullptr ? *base : out_->start;
  fs = Bounded(d.prefix + "Fs", fs);
  vs = Bounded(d.prefix + "vs", vs);
  SetParameter(&p, d.prefix + "Fs", fs);
  SetParameter(&p, d.prefix + "vs", vs);
  double fd = 0, b = 0;
  const bool sliding = measure_ == ScreenMeasure::kWholeRuns && SlidingFree(d);
  if (sliding && FitSliding(data_.clusters, d.sign, fs, vs, &fd, &b) < HUGE_VAL) {
    SetParameter(&p, d.prefix + "Fd", Bounded(d.prefix + "Fd", fd));
    SetParameter(&p, d.prefix + "b", Bounded(d.prefix + "b", b));
  } else {
    GetParameter(p, d.prefix + "Fd", &fd);
    SetParameter(&p, d.prefix + "Fd", std::min(fd, fs));
  }
  return p;
}

double FrictionScreenSearch::Consider(Parameters p, std::optional<double> above) {
  bool exact = true;
  const double measure = Score(p, above.value_or(out_->ranked_after), &exact);
  Take(std::move(p), measure, exact);
  return measure;
}

void FrictionScreenSearch::ConsiderAll(std::vector<Parameters> candidates,
                                       const std::function<double()>& above,
                                       const std::function<void(std::size_t, double)>& measured) {
  const int threads = measure_ == ScreenMeasure::kWindows ? options_.threads : 1;
  const std::size_t chunk = threads == 1 ? 1 : kCandidatesPerThread * threads;
  for (std::size_t i = 0; i < candidates.size(); i += chunk) {
    const double bound = above ? above() : out_->ranked_after;
    if (threads == 1) {
      const double measure = Consider(std::move(candidates[i]), bound);
      if (measured) measured(i, measure);
      continue;
    }
    const std::size_t end = std::min(i + chunk, candidates.size());
    std::vector<Parameters> some(std::make_move_iterator(candidates.begin() + i),
                                 std::make_move_iterator(candidates.begin() + end));
    const auto measures = windows_.MeasureSeveral(some, bound, threads);
    out_->candidates += static_cast<int>(some.size());
    for (std::size_t k = 0; k < some.size(); ++k) {
      Take(std::move(some[k]), measures[k].first, measures[k].second);
      if (measured) measured(i + k, measures[k].first);
    }
  }
}

void FrictionScreenSearch::Take(Parameters p, double measure, bool exact) {
  if (keep_simulated_ && !profiling_) simulated_.Add(measure, exact, p);
  if (measure < out_->ranked_after) {
    out_->ranked_after = measure, out_->start = std::move(p);
    Rebase();  // a set just measured: no simulation
  }
}

bool FrictionScreenSearch::Distinct(const Parameters& a, const Parameters& b) const {
  const auto apart = [&](const std::string& path, double factor) {
    double x = 0, y = 0;
    GetParameter(a, path, &x);
    GetParameter(b, path, &y);
    return std::max(x, y) / std::max(std::min(x, y), 1e-12) > factor;
  };
  for (const Direction& d : directions_) {
    if (apart(d.prefix + "Fs", kDistinctStatic) || apart(d.prefix + "vs", kDistinctStribeck))
      return true;
  }
  return false;
}

FrictionScreen ScreenFrictionStarts(const Parameters& start, const Unit& unit, const FitSpec& spec,
                                    const RefineOptions& options, bool even_if_explained,
                                    int alternatives, ScreenMeasure measure) {
  FrictionScreen out;
  out.start = start;
  FrictionScreenSearch screen(unit, spec, options, measure, alternatives > 0, &out);
  out.chi_square_before = out.chi_square_after = VerdictMeasure(start, unit, spec, options);
  ++out.candidates;
  const char* name = measure == ScreenMeasure::kWindows
                         ? "friction start read off the logs, ranked by windows"
                         : "friction start read off the logs";
  char line[320];
  if (Explains(out.chi_square_before, options) && !even_if_explained) {
    // The fit from it failed the verdict, but the start itself passes: the
    // screen's measure cannot rank a candidate above it.
    std::snprintf(line, sizeof(line),
                  "%s: not screened, the given start explains the runs from their logged starts "
                  "(median reduced chi-square %.3g)",
                  name, out.chi_square_before);
    out.report = line;
    return out;
  }
  const bool windows = measure == ScreenMeasure::kWindows;
  out.ranked_before = out.ranked_after = windows ? screen.Score(start) : out.chi_square_before;
  screen.Rebase();
  if (windows) {
    screen.SearchByWindows(start);
  } else {
    screen.ReadSlides();
    screen.SlidingFromSlides();
    screen.CoarseGrid();
    screen.PatternSearch();
  }
  screen.PickAlternatives(start, alternatives);
  ForgetMoved(start, spec, &out.start);
  for (Parameters& alternative : out.alternatives) ForgetMoved(start, spec, &alternative);
  if (out.profiled) ForgetMoved(start, spec, &*out.profiled);
  out.moved = out.ranked_after < out.ranked_before;
  if (!out.moved) {
    std::snprintf(line, sizeof(line), "%s: no candidate ranks above the given start (%d simulated)",
                  name, out.candidates);
    out.report = line;
    return out;
  }
  if (windows) {
    out.chi_square_after = VerdictMeasure(out.start, unit, spec, options);
    ++out.candidates;
    const std::size_t all =
        FittedRuns(WithRigConditions(start, unit), unit, spec, true, options.lag_starts.get())
            .size();
    const std::size_t ranked =
        SubsetSize(all, static_cast<std::size_t>(options.screen_windows_max));
    std::snprintf(line, sizeof(line),
                  "%s (%zu of %zu): mean square %.3g -> %.3g, median reduced chi-square %.3g -> "
                  "%.3g (%d candidates simulated; windows: %ld simulated, %ld taken unchanged)",
                  name, ranked, all, out.ranked_before, out.ranked_after, out.chi_square_before,
                  out.chi_square_after, out.candidates, screen.windows().windows_simulated(),
                  screen.windows().windows_taken());
  } else {
    out.chi_square_after = out.ranked_after;
    std::snprintf(line, sizeof(line),
                  "%s: median reduced chi-square %.3g -> %.3g "
                  "(%d candidates simulated)",
                  name, out.chi_square_before, out.chi_square_after, out.candidates);
  }
  out.report = line;
  return out;
}

}  // namespace pneumaid::refine_internal
