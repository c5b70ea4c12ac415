// The candidates that a search for starts simulated, kept to pick its
// next-best ones from: each with its measure, or with a lower bound of it
// where the simulation stopped once the candidate measured above the best so
// far (WindowedMeasure's `above`, refine_verdict.h).
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

#include "pneumaid/model/parameters.h"

namespace pneumaid::refine_internal {

class RankedCandidates {
 public:
  // `measure` is the candidate's measure when `exact`, else a lower bound.
  // One whose measure is not finite (it cannot be simulated) is not kept.
  void Add(double measure, bool exact, Parameters p);

  // Hands the candidates to `take` in the order of their measures (the
  // order added on a tie) while `more()` holds. One known by a lower bound
  // is measured whole by `measure` when it comes first and ranked again
  // (dropped when that is not finite), unless `fresh` says that `take`
  // would refuse it anyway (and keeps refusing it). So the order is that of
  // every candidate measured whole, for a fraction of the simulations.
  // `take` may move the candidate out: call this once.
  void TakeInOrder(const std::function<bool()>& more,
                   const std::function<bool(const Parameters&)>& fresh,
                   const std::function<double(const Parameters&)>& measure,
                   const std::function<void(Parameters&)>& take);

 private:
  struct Candidate {
    double measure;
    bool exact;
    Parameters p;
  };
  std::vector<Candidate> candidates_;
};

}  // namespace pneumaid::refine_internal
