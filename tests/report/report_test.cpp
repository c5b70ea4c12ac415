// The HTML report of datasets/paper-rig: one self-contained file (uPlot and
// data inlined, no network reference in any src or href), small, with a plot
// per channel of each validation run and the valve gain, long runs decimated.
// The page's own check runs in headless Chromium from scripts/report-check.sh.
#include "pneumaid/report/report.h"

#include <gtest/gtest.h>

#include <regex>

#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"

namespace pneumaid {
namespace {

const std::string kRoot = PNEUMAID_SOURCE_DIR;

TEST(ReportTest, AUnitsReportIsOneSmallSelfContainedPage) {
  const Unit unit = ReadUnit(kRoot + "/datasets/paper-rig");
  const Parameters params = LoadParams(kRoot + "/datasets/paper-rig/truth.yaml");
  const std::string html = UnitReportHtml(params, unit, ReportOptions{});
  EXPECT_LT(html.size(), 5u << 20);  // issue 15: under 5 MB for 10 experiments at 1 kHz
  EXPECT_NE(html.find("id=\"pneumaid-status\""), std::string::npos);
  EXPECT_NE(html.find("uPlot"), std::string::npos);
  // Offline: no src or href attribute points to the network.
  EXPECT_FALSE(std::regex_search(html, std::regex("(src|href)\\s*=\\s*[\"']?\\s*https?://")));
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  // Two validation runs x five channels, the valve gain, four tube lengths.
  std::size_t plots = 0;
  for (std::size_t at = html.find("<div id=\"plot"); at != std::string::npos;
       at = html.find("<div id=\"plot", at + 1))
    ++plots;
  EXPECT_EQ(plots, 15u);
  EXPECT_NE(html.find("friction.positive.Fs"), std::string::npos);  // the parameter table
  EXPECT_NE(html.find("stroke-100"), std::string::npos);            // every run's metrics
}

TEST(ReportTest, LongRunsAreDecimatedKeepingExtremes) {
  const Unit unit = ReadUnit(kRoot + "/datasets/paper-rig");
  const Parameters params = LoadParams(kRoot + "/datasets/paper-rig/truth.yaml");
  ReportOptions narrow;
  narrow.max_columns = 100;
  const std::string small = UnitReportHtml(params, unit, narrow);
  const std::string full = UnitReportHtml(params, unit, ReportOptions{});
  EXPECT_LT(small.size(), full.size());
  ReportOptions bad;
  bad.max_columns = 3;
  EXPECT_THROW(UnitReportHtml(params, unit, bad), InputError);
}

}  // namespace
}  // namespace pneumaid
