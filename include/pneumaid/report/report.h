// Reports people look at: one self-contained HTML file (scripts, styles and
// data inlined; no network reference) with interactive plots drawn by the
// vendored uPlot (src/report/vendor/uplot, scripts/vendor-uplot.sh) and the
// tables of the text reports. The page checks itself: every plot's canvas
// must have drawn and no script error may occur; the outcome is written into
// the element with id "pneumaid-status" ("OK: N plots" or "FAIL: ...").
#pragma once

#include <string>
#include <vector>

#include "pneumaid/batch/batch.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/model/parameters.h"
#include "pneumaid/validate/validate.h"

namespace pneumaid {

struct ReportOptions {
  // Long runs are decimated for display to this many columns, each keeping
  // the minimum and the maximum of every series in it (so spikes survive).
  int max_columns = 1500;
  // The page's title; default: "pneumaid report: <unit>" ("... fleet",
  // "... diagnose <unit>").
  std::string title;
  // A command's own text report (identify's fits, refine's verdict, ...),
  // shown as it is under the title; empty: none.
  std::string text_report;

  bool IsValid(std::string* error) const;
};

// A unit's report for a parameter set: the parameter table (value, unit,
// standard error, fitted or from the prior), the metrics of every stroke and
// validation run, measured against simulated x, p1, p2, q1, q2 of every
// validation run with their differences (linked time axes and cursors per
// run), the valve gain K_vp with both fitted branches against the measured
// plateaus (seed paper Fig. 3), the friction-velocity map of the stroke logs
// with the fitted Stribeck curve per direction (Figs. 8-9), and the tube's
// step responses with the fitted lag (Figs. 6-7), each where the unit has the
// logs. `simulated`: the runs already simulated with `params` (validate's
// report, its selection of runs), shown instead of every stroke and
// validation run. Throws InputError for bad options.
std::string UnitReportHtml(const Parameters& params, const Unit& unit, const ReportOptions& options,
                           const ValidationReport* simulated = nullptr);

// What a diagnose report shows: the Markdown report of the run
// (DiagnoseResult::MarkdownReport: the conclusion, the residuals per regime,
// the ranking with its evidence), the effects named in the order added, the
// parameter set before and after (the augmented one), and every run
// simulated with both.
struct DiagnoseReportInput {
  std::string markdown;
  std::vector<std::string> named_effects;
  Parameters before_params, after_params;
  ValidationReport before, after;
};

// The page of a diagnose run: the named effects, the RMSE per channel before
// and after, the Markdown report's tables, the augmented parameter table, and
// per validation run (every simulated run when the unit has none) the
// residual measured - simulated before and after of each channel.
std::string DiagnoseReportHtml(const DiagnoseReportInput& input, const Unit& unit,
                               const ReportOptions& options);

// The fleet's page from MergeResults(): units with a parameter set, their
// verdicts, outliers highlighted with the parameters that make them so and
// a plot of each such parameter across the fleet, the failed units with
// their reasons, the fleet's medians and spreads, and a section per unit
// with its parameter values (robust z beside the outlying ones).
std::string FleetReportHtml(const FleetSummary& fleet, const ReportOptions& options);

}  // namespace pneumaid
