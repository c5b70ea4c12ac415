#include "../../src/ident/uniform_clock.h"

#include <gtest/gtest.h>

#include <vector>

#include "pneumaid/io/log_notes.h"

namespace pneumaid::internal {
namespace {

// A 1 ms log that dropped one row (t = 3 ms) and lost eight (t = 6 .. 13 ms):
// read on the median's clock, x interpolated, u held from each sample; only
// the samples inside the long gap are marked as such, not those beside a
// dropped row or at the logged samples either side of the gap.
TEST(UniformClockTest, MarksTheSamplesInsideAGapAndNotBesideADroppedRow) {
  Experiment e;
  std::vector<double> t;
  for (int ms = 0; ms <= 20; ++ms) {
    if (ms == 3 || (ms >= 6 && ms <= 13)) continue;
    t.push_back(ms * 1e-3);
  }
  e.columns["t"] = t;
  std::vector<double> x, u;
  for (double time : t) x.push_back(2 * time), u.push_back(time < 0.010 ? 0.5 : 0.7);
  e.columns["x"] = x;
  e.columns["u"] = u;
  EXPECT_DOUBLE_EQ(MedianInterval(t), 1e-3);
  EXPECT_EQ(UniformPeriod(t), 0);

  std::vector<bool> in_gap;
  const auto resampled = ResampledUniformly(e, &in_gap);
  const auto& clock = resampled->column("t");
  ASSERT_EQ(clock.size(), 21u);
  ASSERT_EQ(in_gap.size(), 21u);
  for (std::size_t k = 0; k < clock.size(); ++k) {
    EXPECT_EQ(in_gap[k], k >= 6 && k <= 13) << "t = " << clock[k];
    EXPECT_NEAR(resampled->column("x")[k], 2 * clock[k], 1e-12) << k;
  }
  EXPECT_EQ(resampled->column("u")[3], 0.5);   // held from t = 2 ms
  EXPECT_EQ(resampled->column("u")[12], 0.5);  // held from t = 5 ms across the gap
  EXPECT_EQ(resampled->column("u")[14], 0.7);
}

}  // namespace
}  // namespace pneumaid::internal
