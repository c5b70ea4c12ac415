// The HTML reports: the unit's (datasets/paper-rig: one self-contained file,
// uPlot and data inlined, no network reference, a plot per channel of each
// validation run, the valve gain, the friction map per direction, the tube's
// step responses, long runs decimated), the diagnose run's (named effect,
// the Markdown report's tables, residuals before and after) and the fleet's
// (datasets/fleet: the outlier highlighted, the failed unit listed). The
// pages' own checks run in headless Chromium from scripts/report-check.sh.
#include "pneumaid/report/report.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <regex>

#include "fleet_results_util.h"
#include "pneumaid/ident/friction_fit.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/model/friction.h"

namespace pneumaid {
namespace {

namespace fs = std::filesystem;
const std::string kRoot = PNEUMAID_SOURCE_DIR;

int Count(const std::string& text, const std::string& what) {
  int n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// Offline: no src or href attribute points to the network, nothing linked.
void ExpectSelfContained(const std::string& html) {
  EXPECT_NE(html.find("id=\"pneumaid-status\""), std::string::npos);
  EXPECT_NE(html.find("uPlot"), std::string::npos);
  EXPECT_FALSE(std::regex_search(html, std::regex("(src|href)\\s*=\\s*[\"']?\\s*https?://")));
  EXPECT_EQ(html.find("<link"), std::string::npos);
  EXPECT_EQ(html.find("<script src"), std::string::npos);
}

TEST(ReportTest, AUnitsReportIsOneSmallSelfContainedPage) {
  const Unit unit = ReadUnit(kRoot + "/datasets/paper-rig");
  const Parameters params = LoadParams(kRoot + "/datasets/paper-rig/truth.yaml");
  ReportOptions options;
  options.text_report = "a <fit> report";
  const std::string html = UnitReportHtml(params, unit, options);
  EXPECT_LT(html.size(), 5u << 20);  // issue 15: under 5 MB for 10 experiments at 1 kHz
  ExpectSelfContained(html);
  // Two validation runs x five channels, the valve gain, the friction map's
  // two directions, four tube lengths.
  EXPECT_EQ(Count(html, "<div id=\"plot"), 17);
  EXPECT_NE(html.find("friction, extending"), std::string::npos);
  EXPECT_NE(html.find("friction, retracting"), std::string::npos);
  EXPECT_NE(html.find("friction.positive.Fs"), std::string::npos);  // the parameter table
  EXPECT_NE(html.find("stroke-100"), std::string::npos);            // every run's metrics
  EXPECT_NE(html.find("a &lt;fit&gt; report"), std::string::npos);  // the command's text
}

// A coefficient the refinement left on a bound has no standard error and so
// no `uncertainty` entry; the provenance says it was fitted, and the table
// must not call it the prior's.
TEST(ReportTest, TheParameterTableTellsACoefficientAtABoundFromThePriors) {
  const Unit unit = ReadUnit(kRoot + "/datasets/paper-rig");
  Parameters params = LoadParams(kRoot + "/datasets/paper-rig/truth.yaml");
  params.uncertainty = {{"friction.positive.Fs", 0.1}};
  params.provenance_yaml = "{refine: {status: converged, at_bound: [\"friction.negative.Fd\"]}}";
  const std::string html = UnitReportHtml(params, unit, ReportOptions{});
  const auto row_of = [&html](const std::string& path) {
    const std::size_t at = html.find("<td class=l>" + path + "</td>");
    return at == std::string::npos ? std::string() : html.substr(at, html.find("</tr>", at) - at);
  };
  EXPECT_NE(row_of("friction.positive.Fs").find(">fitted<"), std::string::npos);
  EXPECT_NE(row_of("friction.negative.Fd").find("fitted, at a bound (no standard error)"),
            std::string::npos);
  EXPECT_NE(row_of("friction.negative.Fs").find("prior / given"), std::string::npos);
  // Provenance that is not ours (no such list, or not YAML at all) marks none.
  for (const char* other : {"{by: hand", "{by: hand, refine: {status: converged}}", "[1, 2]"}) {
    params.provenance_yaml = other;
    EXPECT_EQ(UnitReportHtml(params, unit, ReportOptions{}).find("at a bound"), std::string::npos)
        << other;
  }
}

// A coefficient a fit held (not determined by its logs) says so with why:
// the refinement's (refine.held) even though its `uncertainty` entry is the
// prior's pull; a component fit's (identify's `held`) when the refinement did
// not fit it again. The fitted and the prior's rows stay as they were.
TEST(ReportTest, TheParameterTableNamesTheHeldCoefficientsWithWhy) {
  const Unit unit = ReadUnit(kRoot + "/datasets/paper-rig");
  Parameters params = LoadParams(kRoot + "/datasets/paper-rig/truth.yaml");
  params.uncertainty = {
      {"friction.positive.Fs", 0.1}, {"friction.positive.vs", 0.004}, {"friction.negative.b", 0.2}};
  // friction.negative.b: held by identify, fitted by the refinement since.
  params.provenance_yaml =
      "{held: {friction.negative.vs: \"no slide below 10 mm/s\", friction.positive.vs: "
      "\"read off\", friction.negative.b: \"no slide\", friction.negative.Fd: \"no slide\"}, "
      "refine: {status: converged, free: [friction.negative.Fd], held: "
      "{friction.positive.vs: \"not determined by the fitted runs; regularised toward its "
      "centre\"}}}";
  const std::string html = UnitReportHtml(params, unit, ReportOptions{});
  const auto row_of = [&html](const std::string& path) {
    const std::size_t at = html.find("<td class=l>" + path + "</td>");
    return at == std::string::npos ? std::string() : html.substr(at, html.find("</tr>", at) - at);
  };
  EXPECT_NE(row_of("friction.positive.vs")
                .find("held by the refinement: not determined by the fitted runs; regularised"),
            std::string::npos);
  EXPECT_NE(row_of("friction.negative.vs").find("held by its component fit: no slide below 10"),
            std::string::npos);
  EXPECT_NE(row_of("friction.positive.Fs").find(">fitted<"), std::string::npos);
  EXPECT_NE(row_of("friction.negative.b").find(">fitted<"), std::string::npos);
  EXPECT_NE(row_of("friction.negative.Fs").find("prior / given"), std::string::npos);
  // Freed by the refinement, which gave it no error (no covariance): identify's
  // word no longer holds.
  EXPECT_NE(row_of("friction.negative.Fd").find("refined (no standard error)"), std::string::npos);
  // Grey (class=prior) unless a fit determined it.
  const auto grey = [&html](const std::string& path) {
    const std::size_t at = html.find("<td class=l>" + path + "</td>");
    const std::size_t row = html.rfind("<tr", at);
    return html.compare(row, 16, "<tr class=prior>") == 0;
  };
  EXPECT_TRUE(grey("friction.positive.vs"));
  EXPECT_TRUE(grey("friction.negative.vs"));
  EXPECT_FALSE(grey("friction.negative.b"));
  EXPECT_FALSE(grey("friction.negative.Fd"));
  EXPECT_FALSE(grey("friction.positive.Fs"));
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

TEST(ReportTest, TheFrictionMapHoldsTheSlidesForceBalance) {
  // The map's samples lie on the truth's Stribeck curve within the force
  // noise (paper rig: the truth is the model that wrote the logs).
  const Unit unit = ReadUnit(kRoot + "/datasets/paper-rig");
  const Parameters truth = LoadParams(kRoot + "/datasets/paper-rig/truth.yaml");
  const std::vector<FrictionMapSample> map = FrictionVelocityMap(unit, FrictionFitOptions{});
  ASSERT_GT(map.size(), 100u);
  double sum = 0;
  for (const FrictionMapSample& s : map) {
    const auto c = MakeStribeckCoefficients<double>(s.direction > 0 ? truth.friction.positive
                                                                    : truth.friction.negative);
    EXPECT_GT(s.speed_m_per_s, 0);
    sum += s.friction_N - StribeckMagnitude(s.speed_m_per_s, c);
  }
  EXPECT_LT(std::fabs(sum / map.size()), 0.2);  // N: no bias
}

// A diagnose run's page from a crafted report: the named effect, the
// Markdown's table, list, code and emphasis as HTML (text escaped), and the
// residuals of both validation runs before and after.
TEST(ReportTest, ADiagnosePageShowsTheNamedEffectTheRankingAndTheResiduals) {
  const Unit unit = ReadUnit(kRoot + "/datasets/hidden/valve-lag");
  DiagnoseReportInput input;
  input.markdown =
      "# Diagnose: x\n\nNamed, in order: valve_lag.\n\n### Candidates (best first)\n\n"
      "| effect | held-back gain | named |\n|---|---|---|\n| valve_lag | 74 % | **yes** |\n"
      "| cross_leakage | -14 % | no |\n\nWorst windows:\n\n- step-1 p1 1.2-1.4 s <here>\n\n"
      "```\neffects.valve_lag.tau 0.01 -> 0.025\n```\n#\n## \n";
  input.named_effects = {"valve_lag"};
  input.before_params = LoadParams(kRoot + "/configs/paper.yaml");
  input.after_params = LoadParams(kRoot + "/datasets/hidden/valve-lag/truth.yaml");
  ValidationOptions runs;
  input.before = ValidateUnit(input.before_params, unit, runs);
  input.after = ValidateUnit(input.after_params, unit, runs);
  const std::string html = DiagnoseReportHtml(input, unit, ReportOptions{});
  ExpectSelfContained(html);
  EXPECT_NE(html.find("Named effect: <b>valve_lag</b>"), std::string::npos);
  EXPECT_NE(html.find("<th class=l>held-back gain</th>"), std::string::npos);
  EXPECT_NE(html.find("<td class=l>cross_leakage</td>"), std::string::npos);
  EXPECT_NE(html.find("<td class=l><b>yes</b></td>"), std::string::npos);
  EXPECT_NE(html.find("<li>step-1 p1 1.2-1.4 s &lt;here&gt;</li>"), std::string::npos);
  EXPECT_NE(html.find("<pre>effects.valve_lag.tau 0.01 -&gt; 0.025\n</pre>"), std::string::npos);
  EXPECT_NE(html.find("<h2></h2>\n<h3></h3>"), std::string::npos);   // bare headings
  EXPECT_NE(html.find("effects.valve_lag.tau"), std::string::npos);  // the augmented table
  EXPECT_EQ(Count(html, "<div id=\"plot"), 10);                      // two runs x five channels
  EXPECT_EQ(Count(html, "\"label\":\"before\""), 10);
  EXPECT_EQ(Count(html, "\"label\":\"after\""), 10);
  input.named_effects.clear();
  EXPECT_NE(DiagnoseReportHtml(input, unit, ReportOptions{}).find("No catalog effect named"),
            std::string::npos);
}

TEST(ReportTest, TheFleetPageHighlightsTheOutlierAndListsTheFailedUnit) {
  const std::string results =
      testing::IdentifyBundledFleet(fs::path(::testing::TempDir()) / "report_fleet", "test");
  const std::string html = FleetReportHtml(MergeResults({results}), ReportOptions{});
  ExpectSelfContained(html);
  EXPECT_NE(html.find("13 units with a parameter set, 1 failed, 1 flagged"), std::string::npos);
  // The outlier: its rows highlighted, a plot per parameter that makes it one.
  const std::regex outlier_row("<tr class=outlier><td class=l><a href=\"#unit-PVQ13_0013-2d\">");
  EXPECT_TRUE(std::regex_search(html, outlier_row));
  EXPECT_EQ(Count(html, "<tr class=outlier><td class=l><a href=\"#unit-PVQ13_00"),
            Count(html, "<tr class=outlier><td class=l><a href=\"#unit-PVQ13_0013-2d\""));
  EXPECT_GE(Count(html, "across the fleet\""), 1);
  EXPECT_EQ(Count(html, "<div id=\"plot"), Count(html, "across the fleet\""));
  // The failed unit with its reason; a section per unit.
  EXPECT_TRUE(std::regex_search(
      html, std::regex("<tr class=failed><td class=l>PVQ13-0014</td><td class=l>[^<]*"
                       "step-1.csv:1623: ragged row")));
  EXPECT_EQ(Count(html, "<h3 id=\"unit-"), 13);
}

}  // namespace
}  // namespace pneumaid
