#include "pneumaid/io/units.h"

#include <gtest/gtest.h>

namespace pneumaid {
namespace {

double Convert(const char* symbol, double value) {
  const UnitInfo* unit = FindUnit(symbol);
  EXPECT_NE(unit, nullptr) << symbol;
  return unit ? ToSI(*unit, value, 1.013e5) : 0.0;
}

TEST(UnitsTest, HandValues) {
  EXPECT_DOUBLE_EQ(Convert("mm", 12.5), 0.0125);
  EXPECT_DOUBLE_EQ(Convert("cm", 38), 0.38);
  EXPECT_DOUBLE_EQ(Convert("ms", 250), 0.25);
  EXPECT_DOUBLE_EQ(Convert("bar", 5), 5e5);
  EXPECT_DOUBLE_EQ(Convert("bar_g", 4), 4e5 + 1.013e5);
  EXPECT_DOUBLE_EQ(Convert("kPa", 101.3), 101300.0);
  EXPECT_NEAR(Convert("psi", 14.5038), 1.0e5, 0.5);
  EXPECT_NEAR(Convert("psi_g", 0), 1.013e5, 1e-9);
  EXPECT_DOUBLE_EQ(Convert("l/min", 60), 1e-3);
  EXPECT_DOUBLE_EQ(Convert("L/min", 6), 1e-4);
  EXPECT_DOUBLE_EQ(Convert("m3/h", 3.6), 1e-3);
  EXPECT_DOUBLE_EQ(Convert("g/s", 0.1), 1e-4);
  EXPECT_DOUBLE_EQ(Convert("degC", 20), 293.15);
  EXPECT_DOUBLE_EQ(Convert("cm3", 2), 2e-6);
  EXPECT_DOUBLE_EQ(Convert("g", 150), 0.15);
}

TEST(UnitsTest, UnknownUnitsAndListing) {
  EXPECT_EQ(FindUnit("furlong"), nullptr);
  EXPECT_EQ(FindUnit("BAR"), nullptr);  // case-sensitive
  EXPECT_EQ(AcceptedUnits({Quantity::kTime}), "s, ms");
}

}  // namespace
}  // namespace pneumaid
