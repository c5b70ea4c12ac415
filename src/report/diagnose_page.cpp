// The page of a diagnose run: what was named, the evidence of the Markdown
// report, the augmented parameter set, and the residuals before and after.
#include "html_page.h"
#include "markdown.h"
#include "pneumaid/report/report.h"
#include "report_sections.h"

namespace pneumaid {
namespace {

using namespace report_internal;

const ExperimentValidation* FindRun(const ValidationReport& report, const std::string& id) {
  for (const ExperimentValidation& e : report.experiments) {
    if (e.id == id) return &e;
  }
  return nullptr;
}

// Per run one plot per channel: measured - simulated with the model before
// (grey) and after (red), one run's plots sharing their time axis.
void AddResidualPlots(const DiagnoseReportInput& input, const Unit& unit, HtmlPage* page) {
  page->body() << "<h2>Residuals before and after</h2>\n<p class=note>measured - simulated, "
                  "with the parameter set diagnosed (before) and the augmented set "
                  "(after).</p>\n";
  for (const ExperimentValidation* before : RunsToPlot(input.before, unit)) {
    const ExperimentValidation* after = FindRun(input.after, before->id);
    if (after == nullptr || !before->simulation.ok() || !after->simulation.ok()) {
      const std::string why =
          after == nullptr ? "not simulated with the augmented set"
          : !before->simulation.ok()
              ? "the simulation with the set diagnosed failed: " + before->simulation.message
              : "the simulation with the augmented set failed: " + after->simulation.message;
      page->body() << "<p>" << Html(before->id) << ": " << Html(why) << "</p>\n";
      continue;
    }
    page->body() << "<h3>" << Html(before->id) << "</h3>\n<div class=plots>";
    for (const ChannelView& view : kChannelViews) {
      const auto& measured = before->measured.*(view.values);
      const auto& a = before->simulated.*(view.values);
      const auto& b = after->simulated.*(view.values);
      if (measured.empty() || a.size() != measured.size() || b.size() != measured.size()) continue;
      Plot p;
      p.title = before->id + ": " + view.name + " residual";
      p.group = "residual-" + before->id;
      p.x_label = "t [s]";
      p.y_label = "measured - simulated [" + std::string(view.unit) + "]";
      p.x = before->measured.t_s;
      Series was{"before", "#a0a0a0", {}}, now{"after", "#d62728", {}};
      for (std::size_t i = 0; i < measured.size(); ++i) {
        was.values.push_back((measured[i] - a[i]) * view.scale);
        now.values.push_back((measured[i] - b[i]) * view.scale);
      }
      p.series = {was, now};
      page->AddPlot(std::move(p));
    }
    page->body() << "</div>\n";
  }
}

}  // namespace

std::string DiagnoseReportHtml(const DiagnoseReportInput& input, const Unit& unit,
                               const ReportOptions& options) {
  CheckOptions(options);
  HtmlPage page(options.title.empty() ? "pneumaid diagnose: " + unit.manifest.unit : options.title,
                options.max_columns);
  page.body() << "<div class=named>";
  if (input.named_effects.empty()) {
    page.body() << "No catalog effect named: none explains the gap by the decision rule.";
  } else {
    page.body() << "Named effect" << (input.named_effects.size() > 1 ? "s" : "") << ":";
    for (std::size_t k = 0; k < input.named_effects.size(); ++k)
      page.body() << (k ? ", then " : " ") << "<b>" << Html(input.named_effects[k]) << "</b>";
  }
  page.body() << "</div>\n<p class=note>Unit directory " << Html(unit.directory) << ".</p>\n"
              << TextReport(options.text_report) << MarkdownToHtml(input.markdown)
              << "<h2>Every run, before and after</h2>\n<h3>Before</h3>\n"
              << MetricsTable(input.before) << "<h3>After</h3>\n"
              << MetricsTable(input.after)
              << "<h2>The augmented parameter set</h2>\n<p class=note>SI units, pressures "
                 "absolute; grey rows were not fitted.</p>\n"
              << ParameterTable(input.after_params);
  AddResidualPlots(input, unit, &page);
  return page.Finish();
}

}  // namespace pneumaid
