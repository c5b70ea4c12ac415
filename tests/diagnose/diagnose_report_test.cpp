// The diagnose report's text (DiagnoseResult::MarkdownReport), on a result
// built in code.
#include <gtest/gtest.h>

#include <string>

#include "pneumaid/diagnose/diagnose.h"

namespace pneumaid {
namespace {

// A worst window spans its samples' times; a run of one sample has one time,
// which the report gives as such (it printed "0.00-0.00 s").
TEST(DiagnoseReportTest, AWindowOfOneSampleIsGivenAtItsTime) {
  DiagnoseResult result;
  DiagnoseIteration iteration;
  iteration.where.worst.push_back(ResidualWindow{"step-1", "x", 0.4, 0.6, 2e-4, 1e-4});
  iteration.where.worst.push_back(ResidualWindow{"hold", "x", 0.0, 0.0, 3e-4, -3e-4});
  iteration.where.worst.push_back(ResidualWindow{"end", "x", 12.341, 12.342, 1e-4, 0.0});
  result.iterations.push_back(iteration);
  const std::string text = result.MarkdownReport();
  EXPECT_NE(text.find("- step-1 x 0.40-0.60 s: RMSE 0.2 mm, mean +0.1"), std::string::npos) << text;
  EXPECT_NE(text.find("- hold x at 0.00 s: RMSE 0.3 mm, mean -0.3"), std::string::npos) << text;
  EXPECT_NE(text.find("- end x at 12.34 s:"), std::string::npos) << text;
  EXPECT_EQ(text.find("0.00-0.00"), std::string::npos) << text;
}

}  // namespace
}  // namespace pneumaid
