// The next-best candidates of a search for starts (src/ident/ranked_candidates.h):
// taken in the order of their whole measures, ties in the order added, where
// some are known only by a lower bound until they come first. No simulation:
// a candidate is a parameter set whose positive Fs names it, and its whole
// measure is read off a table.
#include "../../src/ident/ranked_candidates.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <vector>

#include "pneumaid/model/parameters.h"

namespace pneumaid {
namespace {

Parameters Named(double id) {
  Parameters p;
  p.friction.positive.static_force_N = id;
  return p;
}

double Id(const Parameters& p) { return p.friction.positive.static_force_N; }

struct Taken {
  std::vector<double> ids;  // in the order taken
  int measured = 0;         // whole measures asked for
};

// Takes up to `count` candidates, refusing those in `refused`.
Taken TakeFrom(refine_internal::RankedCandidates& ranked, const std::map<double, double>& whole,
               std::size_t count, const std::vector<double>& refused = {}) {
  Taken out;
  const auto is_refused = [&](const Parameters& p) {
    for (double id : refused)
      if (Id(p) == id) return true;
    return false;
  };
  ranked.TakeInOrder([&] { return out.ids.size() < count; },
                     [&](const Parameters& p) { return !is_refused(p); },
                     [&](const Parameters& p) {
                       ++out.measured;
                       return whole.at(Id(p));
                     },
                     [&](Parameters& p) {
                       if (!is_refused(p)) out.ids.push_back(Id(p));
                     });
  return out;
}

TEST(RankedCandidatesTest, AllMeasuredWholeTheyComeInTheOrderOfTheirMeasuresTiesAsAdded) {
  refine_internal::RankedCandidates ranked;
  const std::map<double, double> whole = {{1, 5.0}, {2, 3.0}, {3, 5.0}, {4, 1.0}, {5, 3.0}};
  for (const auto& [id, measure] : whole) ranked.Add(measure, true, Named(id));
  const Taken taken = TakeFrom(ranked, whole, 5);
  EXPECT_EQ(taken.ids, (std::vector<double>{4, 2, 5, 1, 3}));
  EXPECT_EQ(taken.measured, 0);
}

// Candidate 2 is known by a bound of 2 (whole: 6), candidate 4 by 0.5 (whole:
// 1.5), candidate 5 by 4 (whole: 4, a tie with candidate 1 added before it).
TEST(RankedCandidatesTest, ABoundIsMeasuredWholeWhenItComesFirstAndRankedAgain) {
  const std::map<double, double> whole = {{1, 4.0}, {2, 6.0}, {3, 1.0}, {4, 1.5}, {5, 4.0}};
  refine_internal::RankedCandidates ranked;
  ranked.Add(4.0, true, Named(1));
  ranked.Add(2.0, false, Named(2));
  ranked.Add(1.0, true, Named(3));
  ranked.Add(0.5, false, Named(4));
  ranked.Add(4.0, false, Named(5));
  const Taken all = TakeFrom(ranked, whole, 5);
  EXPECT_EQ(all.ids, (std::vector<double>{3, 4, 1, 5, 2}));
  EXPECT_EQ(all.measured, 3);
}

TEST(RankedCandidatesTest, ItStopsWhenEnoughAreTakenAndMeasuresNoMoreThanItNeeds) {
  const std::map<double, double> whole = {{1, 1.0}, {2, 2.0}, {3, 7.0}, {4, 3.0}};
  refine_internal::RankedCandidates ranked;
  ranked.Add(1.0, true, Named(1));
  ranked.Add(1.5, false, Named(2));  // measured whole: it comes before 4's 3
  ranked.Add(2.5, false, Named(3));  // never: two are taken before it comes first
  ranked.Add(3.0, true, Named(4));
  const Taken two = TakeFrom(ranked, whole, 2);
  EXPECT_EQ(two.ids, (std::vector<double>{1, 2}));
  EXPECT_EQ(two.measured, 1);
}

TEST(RankedCandidatesTest, OneThatWouldBeRefusedIsNotMeasuredAndOneThatCannotBeIsDropped) {
  const std::map<double, double> whole = {{1, 2.0}, {2, 3.0}, {3, HUGE_VAL}, {4, 5.0}};
  refine_internal::RankedCandidates ranked;
  ranked.Add(1.0, false, Named(1));  // refused: never measured whole
  ranked.Add(3.0, true, Named(2));
  ranked.Add(0.5, false, Named(3));  // cannot be simulated whole: dropped
  ranked.Add(NAN, true, Named(5));   // not kept at all
  ranked.Add(HUGE_VAL, true, Named(6));
  ranked.Add(5.0, true, Named(4));
  const Taken taken = TakeFrom(ranked, whole, 3, {1});
  EXPECT_EQ(taken.ids, (std::vector<double>{2, 4}));
  EXPECT_EQ(taken.measured, 1);  // candidate 3 only
}

}  // namespace
}  // namespace pneumaid
