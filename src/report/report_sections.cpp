#include "report_sections.h"

#include <map>
#include <set>
#include <vector>

#include "pneumaid/io/input_error.h"
#include "pneumaid/io/json.h"
#include "pneumaid/io/provenance.h"
#include "pneumaid/model/effects.h"
#include "pneumaid/model/parameter_table.h"

namespace pneumaid {

bool ReportOptions::IsValid(std::string* error) const {
  if (max_columns < 10) {
    if (error != nullptr) *error = "max_columns must be >= 10";
    return false;
  }
  return true;
}

}  // namespace pneumaid

namespace pneumaid::report_internal {

void CheckOptions(const ReportOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw InputError("report options", 0, 0, error);
}

// The coefficients the refinement left on a bound of their range, from the
// set's provenance (refine.at_bound): fitted, but without a standard error,
// so without an `uncertainty` entry. Empty when the provenance has none.
std::set<std::string> AtBound(const Parameters& params) {
  const std::vector<std::string> paths =
      ProvenanceList(params.provenance_yaml, "refine", "at_bound");
  return {paths.begin(), paths.end()};
}

// Where a parameter's value comes from, as the table's source column says it:
// held by the refinement (refine.held: its `uncertainty` is the prior's pull),
// fitted (an `uncertainty` entry), fitted on a bound (refine.at_bound), held
// by a component fit that ran (identify's `held`) and not freed by the
// refinement since (refine.free), refined without a standard error (freed,
// but the refinement gave no covariance), else the prior or given.
// Only the fitted ones are a fit's rows (the held ones grey, as the prior's).
class ValueSource {
 public:
  explicit ValueSource(const Parameters& params)
      : params_(params),
        at_bound_(AtBound(params)),
        refine_held_(ProvenanceStrings(params.provenance_yaml, "refine", "held")),
        identify_held_(ProvenanceStrings(params.provenance_yaml, "", "held")) {
    for (const std::string& path : ProvenanceList(params.provenance_yaml, "refine", "free")) {
      identify_held_.erase(path);
      refine_free_.insert(path);
    }
  }

  struct Source {
    std::string text;  // the source column
    bool fitted;       // the row is a fit's
  };
  Source Of(const std::string& path) const {
    if (const auto held = refine_held_.find(path); held != refine_held_.end())
      return {"held by the refinement: " + held->second, false};
    if (params_.uncertainty.count(path) > 0) return {"fitted", true};
    if (at_bound_.count(path) > 0) return {"fitted, at a bound (no standard error)", true};
    if (refine_free_.count(path) > 0) return {"refined (no standard error)", true};
    if (const auto held = identify_held_.find(path); held != identify_held_.end())
      return {"held by its component fit: " + held->second, false};
    return {"prior / given", false};
  }

 private:
  const Parameters& params_;
  std::set<std::string> at_bound_, refine_free_;
  std::map<std::string, std::string> refine_held_, identify_held_;
};

std::string ParameterTable(const Parameters& params) {
  std::ostringstream out;
  out << "<table><tr><th class=l>parameter</th><th>value</th><th class=l>unit</th>"
         "<th>standard error</th><th class=l>source</th></tr>\n";
  const ValueSource source(params);
  const auto row = [&](const std::string& path, double value, const std::string& unit) {
    const auto error = params.uncertainty.find(path);
    const bool with_error = error != params.uncertainty.end();
    const ValueSource::Source from = source.Of(path);
    out << "<tr" << (from.fitted ? "" : " class=prior") << "><td class=l>" << Html(path)
        << "</td><td>" << Printf("%.6g", value) << "</td><td class=l>" << Html(unit) << "</td><td>"
        << (with_error ? Printf("%.3g", error->second) : "") << "</td><td class=l>"
        << Html(from.text) << "</td></tr>\n";
  };
  for (const ScalarParameterInfo& info : ScalarParameterTable())
    row(info.path, info.get(params), info.unit);
  for (const auto& [effect, values] : params.effects) {
    for (const auto& [name, value] : values) {
      std::string unit;
      for (const EffectParameterInfo& p : FindEffect(effect)->parameters)
        if (name == p.name) unit = p.unit;
      row("effects." + effect + "." + name, value, unit);
    }
  }
  out << "</table>\n";
  return out.str();
}

std::string MetricsTable(const ValidationReport& report) {
  std::ostringstream out;
  out << "<table><tr><th class=l>run</th><th class=l>channel</th><th>RMSE</th>"
         "<th>max |error|</th><th>fit %</th></tr>\n";
  for (const ExperimentValidation& e : report.experiments) {
    if (!e.simulation.ok()) {
      out << "<tr><td class=l>" << Html(e.id)
          << "</td><td class=l colspan=4>simulation failed: " << Html(e.simulation.message)
          << "</td></tr>\n";
      continue;
    }
    for (const ChannelView& view : kChannelViews) {
      const auto m = e.channels.find(view.name);
      if (m == e.channels.end()) continue;
      const auto& fit = m->second.nrmse_fit_percent;
      out << "<tr><td class=l>" << Html(e.id) << "</td><td class=l>" << view.name << "</td>"
          << Printf("<td>%.4g %s</td><td>%.4g %s</td>", m->second.rmse * view.scale, view.unit,
                    m->second.max_abs * view.scale, view.unit)
          << "<td>" << (fit ? FormatSignificant(*fit, 4) : "-") << "</td></tr>\n";
    }
  }
  out << "</table>\n";
  return out.str();
}

std::string TextReport(const std::string& text) {
  return text.empty() ? ""
                      : "<details><summary>The command's report</summary><pre>" + Html(text) +
                            "</pre></details>\n";
}

std::vector<const ExperimentValidation*> RunsToPlot(const ValidationReport& report,
                                                    const Unit& unit) {
  std::vector<const ExperimentValidation*> validation, all;
  for (const ExperimentValidation& e : report.experiments) {
    all.push_back(&e);
    for (const Experiment& x : unit.experiments) {
      if (x.entry.id == e.id && x.entry.kind == ExperimentKind::kValidation)
        validation.push_back(&e);
    }
  }
  return validation.empty() ? all : validation;
}

}  // namespace pneumaid::report_internal
