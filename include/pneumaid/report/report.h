// Reports people look at: one self-contained HTML file (scripts, styles and
// data inlined; no network reference) with interactive plots drawn by the
// vendored uPlot (src/report/vendor/uplot, scripts/vendor-uplot.sh) and the
// tables of the text reports. The page checks itself: every plot's canvas
// must have drawn and no script error may occur; the outcome is written into
// the element with id "pneumaid-status" ("OK: N plots" or "FAIL: ...").
#pragma once

#include <string>

#include "pneumaid/io/rig_data.h"
#include "pneumaid/model/parameters.h"

namespace pneumaid {

struct ReportOptions {
  // Long runs are decimated for display to this many columns, each keeping
  // the minimum and the maximum of every series in it (so spikes survive).
  int max_columns = 1500;
  std::string title;  // default: "pneumaid report: <unit>"

  bool IsValid(std::string* error) const;
};

// A unit's report for a parameter set: the parameter table (value, unit,
// standard error, fitted or from the prior), the measured against simulated
// x, p1, p2, q1, q2 of every stroke and validation run with their
// differences (linked time axes and cursors per run), the run metrics, and
// the valve gain K_vp with both fitted branches against the measured
// plateaus when the unit has valve logs. Throws InputError for bad options.
std::string UnitReportHtml(const Parameters& params, const Unit& unit,
                           const ReportOptions& options);

}  // namespace pneumaid
