#include "ranked_candidates.h"

#include <cmath>
#include <queue>
#include <utility>

namespace pneumaid::refine_internal {

void RankedCandidates::Add(double measure, bool exact, Parameters p) {
  if (!std::isfinite(measure)) return;
  candidates_.push_back({measure, exact, std::move(p)});
}

void RankedCandidates::TakeInOrder(const std::function<bool()>& more,
                                   const std::function<bool(const Parameters&)>& fresh,
                                   const std::function<double(const Parameters&)>& measure,
                                   const std::function<void(Parameters&)>& take) {
  struct Ranked {
    double measure;
    std::size_t index;  // into candidates_
    bool operator>(const Ranked& o) const {
      return measure != o.measure ? measure > o.measure : index > o.index;
    }
  };
  std::priority_queue<Ranked, std::vector<Ranked>, std::greater<>> queue;
  for (std::size_t i = 0; i < candidates_.size(); ++i) queue.push({candidates_[i].measure, i});
  while (!queue.empty() && more()) {
    Candidate& next = candidates_[queue.top().index];
    const std::size_t index = queue.top().index;
    queue.pop();
    if (next.exact) {
      take(next.p);
      continue;
    }
    if (!fresh(next.p)) continue;
    next.measure = measure(next.p);
    next.exact = true;
    if (std::isfinite(next.measure)) queue.push({next.measure, index});
  }
}

}  // namespace pneumaid::refine_internal
