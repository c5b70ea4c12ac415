#include "windowed_measures.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>

#include "../util/run_all.h"
#include "pneumaid/model/parameter_table.h"
#include "refine_residual.h"
#include "refine_solve.h"

namespace pneumaid::refine_internal {

WindowedMeasures::WindowedMeasures(const Unit& unit, const FitSpec& spec,
                                   const RefineOptions& options)
    : unit_(unit), spec_(spec), options_(options) {}

double WindowedMeasures::Measure(const Parameters& params, double above, bool* exact) {
  Measured m;
  bool is_exact = true;
  const double measure =
      MeasureInto(params, above, &is_exact, &m, &windows_simulated_, &windows_taken_);
  if (exact != nullptr) *exact = is_exact;
  last_.clear();
  if (std::isfinite(measure) && is_exact) last_.push_back(std::move(m));
  return measure;
}

std::vector<std::pair<double, bool>> WindowedMeasures::MeasureSeveral(
    const std::vector<Parameters>& candidates, double above, int threads) {
  const std::size_t n = candidates.size();
  std::vector<std::pair<double, bool>> measures(n, {HUGE_VAL, true});
  std::vector<Measured> measured(n);
  std::vector<long> simulated(n, 0), taken(n, 0);
  std::vector<std::function<void()>> tasks;
  for (std::size_t i = 0; i < n; ++i) {
    tasks.push_back([&, i] {
      measures[i].first = MeasureInto(candidates[i], above, &measures[i].second, &measured[i],
                                      &simulated[i], &taken[i]);
    });
  }
  internal::RunAll(&tasks, threads);
  last_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    windows_simulated_ += simulated[i];
    windows_taken_ += taken[i];
    if (std::isfinite(measures[i].first) && measures[i].second)
      last_.push_back(std::move(measured[i]));
  }
  return measures;
}

double WindowedMeasures::MeasureInto(const Parameters& params, double above, bool* exact,
                                     Measured* out, long* simulated_windows,
                                     long* taken_windows) const {
  *exact = true;
  const auto max_windows = static_cast<std::size_t>(options_.screen_windows_max);
  const FittedRunSet windows(params, unit_, spec_, options_, true, max_windows);
  const Parameters simulated = windows.Simulated();
  // What a simulation would refuse, whatever the windows taken say.
  if (!Validate(simulated).empty() || StopRequested(options_)) return HUGE_VAL;
  const std::size_t n = windows.runs().size();
  Measured m;
  m.static_force_N[0] = simulated.friction.positive.static_force_N;
  m.static_force_N[1] = simulated.friction.negative.static_force_N;
  m.squares.assign(n, 0.0);
  m.use.resize(n);
  long rows = 0;
  for (const FitExperiment& w : windows.runs()) {
    m.rows.push_back(w.data_rows());
    rows += w.data_rows();
  }
  if (rows == 0) return HUGE_VAL;

  // The windows the base gives, counted first.
  std::vector<bool> known(n, false);
  double squares = 0;
  const int side = base_ && base_->rows == m.rows ? SideApartFromBase(params) : -1;
  if (side >= 0) {
    for (std::size_t k = 0; k < n; ++k) {
      const FrictionUse& use = base_->use[k];
      if (!use.Unaffected(side, m.static_force_N[side]) ||
          !use.Unaffected(side, base_->static_force_N[side]))
        continue;
      known[k] = true;
      m.squares[k] = base_->squares[k];
      m.use[k] = base_->use[k];
      squares += m.squares[k];
      ++*taken_windows;
    }
  }
  for (std::size_t k = 0; k < n; ++k) {
    if (known[k]) continue;
    // Windows are left to simulate: above the bound already, the measure is too.
    if (squares / static_cast<double>(rows) > above) {
      *exact = false;
      return squares / static_cast<double>(rows);
    }
    const Eigen::VectorXd r = windows.Residuals(k, &m.use[k]);
    ++*simulated_windows;
    const auto data = r.head(m.rows[k]);
    if (!data.allFinite()) return HUGE_VAL;
    m.squares[k] = data.squaredNorm();
    squares += m.squares[k];
  }
  double total = 0;  // in the windows' order, whichever were simulated
  for (const double s : m.squares) total += s;
  m.params = params;
  *out = std::move(m);
  return total / static_cast<double>(rows);
}

void WindowedMeasures::Rebase(const Parameters& params) {
  const auto same = [&params](const Measured& m) { return SameValues(m.params, params); };
  auto found = std::find_if(last_.begin(), last_.end(), same);
  if (found == last_.end()) {
    Measure(params);
    found = std::find_if(last_.begin(), last_.end(), same);
  }
  base_.reset();  // none when `params` cannot be simulated
  if (found != last_.end()) {
    base_ = std::move(*found);
    last_.erase(found);
  }
}

int WindowedMeasures::SideApartFromBase(const Parameters& params) const {
  for (const int side : {0, 1}) {
    Parameters same = params;  // `params` with the base's friction on `side`
    if (side == 0) {
      same.friction.positive = base_->params.friction.positive;
    } else {
      same.friction.negative = base_->params.friction.negative;
    }
    if (SameValues(same, base_->params)) return side;
  }
  return -1;
}

}  // namespace pneumaid::refine_internal
