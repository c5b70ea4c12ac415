// What the friction fit reads off the stroke logs before it fits
// (src/ident/friction_starts.h, ReadOffLogs): which coefficients the logs
// give, and which they leave at the fallback. Force-balance samples drawn
// from a known Stribeck curve (no simulation): the closed form is the truth.
#include "../../src/ident/friction_starts.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "pneumaid/model/friction.h"

namespace pneumaid {
namespace {

using friction_internal::Block;
using friction_internal::LogsReading;
using friction_internal::ReadOffLogs;
using friction_internal::StrokeData;

constexpr double kFs = 12.0, kFd = 2.0, kB = 8.0, kVs = 5e-3;

// The model's Stribeck magnitude (model/friction.h) of coefficients `c` at speed `v`.
double Stribeck(const Block& c, double v) {
  return StribeckMagnitude(v, MakeStribeckCoefficients<double>(friction_internal::Unpack(c)));
}

// One smooth slide per speed band: the force balance of a rod sliding at
// speeds from `slowest` to `fastest` [m/s] in `direction`, the friction the
// paper's Stribeck curve with 0.05 N of seeded noise.
internal::SlideCluster Slide(int direction, double slowest, double fastest, unsigned seed) {
  std::mt19937 random(seed);
  std::normal_distribution<double> noise(0.0, 0.05);
  internal::SlideCluster c;
  c.direction = direction;
  for (int i = 0; i < 200; ++i) {
    const double v = slowest * std::pow(fastest / slowest, i / 199.0);
    c.speed_m_per_s.push_back(v);
    c.friction_N.push_back(Stribeck({kFs, kFd, kB, kVs}, v) + noise(random));
    c.weight.push_back(1 / 0.05);
    c.sample.push_back(static_cast<std::size_t>(i));
  }
  return c;
}

// Breakaways of `direction` at Fs: segments stuck from the start.
void AddBreakaways(int direction, StrokeData* data) {
  for (int k = 0; k < 5; ++k) {
    friction_internal::Segment s{};
    s.direction = direction;
    s.breakaway_force_N = kFs + 0.1 * (k - 2);
    data->segments.push_back(s);
  }
}

const Block kFallback = {10.0, 5.0, 5.0, 0.01};

TEST(FrictionStartsTest, SlidesThroughTheStribeckRegionGiveEveryCoefficient) {
  StrokeData data;
  AddBreakaways(+1, &data);
  data.clusters.push_back(Slide(+1, 0.5e-3, 0.1, 1));
  const LogsReading r = ReadOffLogs(data, +1, kFallback);
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(r.read[i]) << i;
  EXPECT_NEAR(r.value[0], kFs, 1e-9);
  EXPECT_NEAR(r.error[0], 1.2533 * 1.4826 * 0.1 / std::sqrt(5.0), 1e-9);
  // vs within the grid's step (a factor 1.21); Fd and b make up for the
  // rest, so the curve read follows the true one over the slides' speeds
  // within 5 % of the drop (0.4 N measured, where the curve is steepest).
  EXPECT_NEAR(r.value[3], kVs, 0.21 * kVs);
  for (const double v : Slide(+1, 0.5e-3, 0.1, 1).speed_m_per_s) {
    EXPECT_NEAR(Stribeck(r.value, v), Stribeck({kFs, kFd, kB, kVs}, v), 0.05 * (kFs - kFd)) << v;
  }
}

// Logged only from 3 vs up the slides still give Fd and b, and vs from the
// Stribeck term's tail (a 1e-4 of the drop at 3 vs, 0.05 N of noise here):
// a reading, but a coarse one.
TEST(FrictionStartsTest, SlidesAboveTheStribeckRegionGiveTheSlidingFriction) {
  StrokeData data;
  AddBreakaways(+1, &data);
  data.clusters.push_back(Slide(+1, 3 * kVs, 0.1, 2));
  const LogsReading r = ReadOffLogs(data, +1, kFallback);
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(r.read[i]) << i;
  EXPECT_NEAR(r.value[1], kFd, 0.1 * kFd);
  EXPECT_NEAR(r.value[2], kB, 0.1 * kB);
}

// Breakaways without smooth slides read Fs alone; slides without breakaways
// read Fd, b and vs at the fallback's Fs.
TEST(FrictionStartsTest, BreakawaysAndSlidesAreReadEachOnItsOwn) {
  StrokeData breakaways;
  AddBreakaways(+1, &breakaways);
  const LogsReading fs_only = ReadOffLogs(breakaways, +1, kFallback);
  EXPECT_TRUE(fs_only.read[0]);
  EXPECT_NEAR(fs_only.value[0], kFs, 1e-9);
  for (int i = 1; i < 4; ++i) {
    EXPECT_FALSE(fs_only.read[i]) << i;
    EXPECT_EQ(fs_only.value[i], kFallback[i]) << i;
  }
  StrokeData slides;
  slides.clusters.push_back(Slide(+1, 0.5e-3, 0.1, 4));
  const LogsReading sliding = ReadOffLogs(slides, +1, kFallback);
  EXPECT_FALSE(sliding.read[0]);
  EXPECT_EQ(sliding.value[0], kFallback[0]);
  EXPECT_EQ(sliding.error[0], 0.0);
  for (int i = 1; i < 4; ++i) EXPECT_TRUE(sliding.read[i]) << i;
}

// With fewer than three breakaways mid-stroke, Fs is the median of the
// breakaways at the stroke ends.
TEST(FrictionStartsTest, FewBreakawaysMidStrokeReadFsAtTheStops) {
  StrokeData data;
  friction_internal::Segment one{};
  one.direction = -1;
  one.breakaway_force_N = 30.0;  // one mid-stroke breakaway: too few
  data.segments.push_back(one);
  data.end_breakaway_N[1] = {8.0, 9.0, 9.5, 10.0, 40.0};
  const LogsReading r = ReadOffLogs(data, -1, kFallback);
  EXPECT_TRUE(r.read[0]);
  EXPECT_DOUBLE_EQ(r.value[0], 9.5);
  EXPECT_NEAR(r.error[0], 1.2533 * 1.4826 * 0.5 / std::sqrt(5.0), 1e-12);
}

// A direction without breakaways or slides reads nothing: the fallback, no error.
TEST(FrictionStartsTest, ADirectionWithoutSlidesReadsNothing) {
  StrokeData data;
  AddBreakaways(+1, &data);
  data.clusters.push_back(Slide(+1, 0.5e-3, 0.1, 3));
  const LogsReading r = ReadOffLogs(data, -1, kFallback);
  for (int i = 0; i < 4; ++i) {
    EXPECT_FALSE(r.read[i]) << i;
    EXPECT_EQ(r.value[i], kFallback[i]) << i;
    EXPECT_EQ(r.error[i], 0.0) << i;
  }
}

}  // namespace
}  // namespace pneumaid
