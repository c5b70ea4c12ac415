// Sections that more than one report page shows (internal to src/report/):
// the channels as displayed, the parameter table, the metrics table of
// simulated runs, a command's text report.
#pragma once

#include <string>
#include <vector>

#include "html_page.h"
#include "pneumaid/model/parameters.h"
#include "pneumaid/report/report.h"
#include "pneumaid/trajectory.h"
#include "pneumaid/validate/validate.h"

namespace pneumaid::report_internal {

struct ChannelView {
  const char* name;
  std::vector<double> Trajectory::*values;
  const char* unit;
  double scale;  // SI -> display
};
inline const ChannelView kChannelViews[] = {{"x", &Trajectory::x_m, "mm", 1e3},
                                            {"p1", &Trajectory::p1_Pa, "bar abs", 1e-5},
                                            {"p2", &Trajectory::p2_Pa, "bar abs", 1e-5},
                                            {"q1", &Trajectory::q1_kg_per_s, "g/s", 1e3},
                                            {"q2", &Trajectory::q2_kg_per_s, "g/s", 1e3}};

// Throws InputError("report options") for options that are not valid.
void CheckOptions(const ReportOptions& options);

// Value, unit, standard error and source (fitted, or the prior / the rig:
// grey) of every scalar parameter and effect parameter.
std::string ParameterTable(const Parameters& params);

// RMSE, max |error| and fit % per run and channel, in display units.
std::string MetricsTable(const ValidationReport& report);

// A command's text report, preformatted and folded; empty for no text.
std::string TextReport(const std::string& text);

// The validation runs of `report` that the unit logged as validation runs,
// or every run of it when there are none.
std::vector<const ExperimentValidation*> RunsToPlot(const ValidationReport& report,
                                                    const Unit& unit);

}  // namespace pneumaid::report_internal
