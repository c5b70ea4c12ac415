#include "../../src/ident/uniform_clock.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
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

// A logger's clock that stamps rows up to 9 % of an interval off its 1 ms
// grid: the log is on that grid (its mean interval); a stamp 12 % off is
// not. One row lost moves the stamps half an interval or more from the grid
// through the ends, wherever it was.
TEST(UniformClockTest, StampsWithJitterAreOnTheGridALostRowIsNot) {
  std::vector<double> t;
  for (int ms = 0; ms <= 1000; ++ms) t.push_back(ms * 1e-3 + (ms % 7 - 3) * 0.03e-3);
  t.front() = 0, t.back() = 1.0;
  EXPECT_DOUBLE_EQ(UniformPeriod(t), 1e-3);
  std::vector<double> late = t;
  late[500] = 0.5 + 0.12e-3;  // 12 % of an interval off the grid: over kStampJitter
  EXPECT_EQ(UniformPeriod(late), 0.0);
  for (std::size_t k : {std::size_t{1}, std::size_t{500}, std::size_t{999}}) {
    std::vector<double> lost = t;
    lost.erase(lost.begin() + static_cast<std::ptrdiff_t>(k));
    EXPECT_EQ(UniformPeriod(lost), 0.0) << "row " << k << " lost";
  }
}

// A clock whose intervals spread over 0.6 to 1.4 ms is irregular (replayed
// as logged), also where it lost rows; a uniform grid is not, nor a uniform
// grid that lost rows, stamped with jitter or not (read on the grid's clock).
TEST(UniformClockTest, AClockThatKeepsNoTimeIsIrregularALossyGridIsNot) {
  std::vector<double> t = {0.0};
  for (int k = 1; k <= 1000; ++k) t.push_back(t.back() + (1.0 + 0.4 * std::sin(2.7 * k)) * 1e-3);
  EXPECT_TRUE(IrregularClock(t));
  std::vector<double> lost = t;
  lost.erase(lost.begin() + 500);
  EXPECT_TRUE(IrregularClock(lost));
  std::vector<double> grid;
  for (int ms = 0; ms <= 1000; ++ms) grid.push_back(ms * 1e-3 + (ms % 7 - 3) * 0.01e-3);
  EXPECT_FALSE(IrregularClock(grid));  // on the grid (UniformPeriod)
  grid.erase(grid.begin() + 500);
  grid.erase(grid.begin() + 300);
  EXPECT_FALSE(IrregularClock(grid));  // a lossy grid
  grid[200] += 0.12e-3;
  EXPECT_TRUE(IrregularClock(grid));  // a stamp 12 % off the grid
  EXPECT_FALSE(IrregularClock({0.0}));
  // A clock whose intervals spread by +-5 % only drifts off any grid.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> stretch(0.95, 1.05);
  std::vector<double> drifting = {0.0};
  for (int k = 1; k <= 1000; ++k) drifting.push_back(drifting.back() + stretch(rng) * 1e-3);
  EXPECT_EQ(UniformPeriod(drifting), 0.0);
  EXPECT_TRUE(IrregularClock(drifting));
}

}  // namespace
}  // namespace pneumaid::internal
