// Refinement's stopping verdict (src/ident/refine_verdict.h): the runs'
// median reduced chi-square and the misfits it reports, in closed form.
#include "../../src/ident/refine_verdict.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace pneumaid {
namespace {

ChannelMisfit Misfit(const std::string& run, double chi_square, int samples, double worst = 0,
                     double from_s = 0) {
  ChannelMisfit m;
  m.run = run;
  m.channel = "x";
  m.reduced_chi_square = chi_square;
  m.samples = samples;
  m.worst_reduced_chi_square = worst;
  m.worst_from_s = from_s;
  m.worst_to_s = from_s + 0.5;
  return m;
}

// Run "a", cut by a logger's pause: 900 rows at 1 and 100 at 11 are one run
// at 2 (not 6, the pieces' plain mean); with "b" at 3 and "c" at 0.5 the
// median is 2.
std::vector<ChannelMisfit> PausedRun() {
  return {Misfit("a", 1.0, 900, 1.5, 0.2), Misfit("a", 11.0, 100, 20.0, 3.1),
          Misfit("b", 3.0, 1000), Misfit("c", 0.5, 1000)};
}

TEST(RefineVerdictTest, APausedRunsPiecesCountByTheirRows) {
  EXPECT_DOUBLE_EQ(refine_internal::MedianRunChiSquare(PausedRun()), 2.0);
}

TEST(RefineVerdictTest, APausedRunIsReportedOnceWithItsWorstPiecesWindow) {
  RefineResult r;
  r.status = FitStatus::kConverged;
  r.misfits = PausedRun();
  RefineOptions options;
  options.acceptable_reduced_chi_square = 1.5;
  refine_internal::Judge(options, &r);
  ASSERT_EQ(r.misfits.size(), 3u);
  EXPECT_DOUBLE_EQ(r.reduced_chi_square, 2.0);
  EXPECT_EQ(r.status, FitStatus::kNotExplained);
  const ChannelMisfit& a = r.misfits[1];  // sorted worst first: b 3, a 2, c 0.5
  EXPECT_EQ(a.run, "a");
  EXPECT_DOUBLE_EQ(a.reduced_chi_square, 2.0);
  EXPECT_EQ(a.samples, 1000);
  EXPECT_DOUBLE_EQ(a.worst_reduced_chi_square, 20.0);
  EXPECT_DOUBLE_EQ(a.worst_from_s, 3.1);
  EXPECT_NE(r.reason.find("b x: 3"), std::string::npos) << r.reason;
}

}  // namespace
}  // namespace pneumaid
