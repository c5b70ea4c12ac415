// The fleet's page: who was identified, who failed, who stands out and why.
#include <cctype>
#include <cmath>
#include <set>

#include "html_page.h"
#include "pneumaid/report/report.h"
#include "report_sections.h"

namespace pneumaid {
namespace {

using namespace report_internal;

// An id for a unit's section: its name's letters and digits, '_' for the
// rest, and a hex code of what was replaced (so "a-b" and "a_b" differ).
std::string Anchor(const std::string& unit) {
  std::string id = "unit-", codes;
  for (char c : unit) {
    const bool plain = std::isalnum(static_cast<unsigned char>(c));
    id += plain ? c : '_';
    if (!plain) codes += Printf("%02x", static_cast<unsigned char>(c));
  }
  return codes.empty() ? id : id + "-" + codes;
}

const FleetParameter* FindParameter(const FleetSummary& fleet, const std::string& path) {
  for (const FleetParameter& p : fleet.parameters) {
    if (p.path == path) return &p;
  }
  return nullptr;
}

// Each parameter that makes some unit an outlier, across the fleet: every
// unit's value (outliers red), the median and median +- limit x MAD.
void AddOutlierPlots(const FleetSummary& fleet, HtmlPage* page) {
  std::set<std::string> paths;
  for (const FleetUnit& u : fleet.units) {
    for (const auto& [path, z] : u.outlying) paths.insert(path);
  }
  if (paths.empty()) return;
  page->body() << "<div class=plots>";
  for (const std::string& path : paths) {
    const FleetParameter* parameter = FindParameter(fleet, path);
    Plot p;
    p.title = path + " across the fleet";
    p.x_label = "unit (in the units table's order)";
    p.y_label = path;
    Series units{"units", "#1f77b4", {}, 1, true}, outliers{"outliers", "#d62728", {}, 1, true},
        median{"median", "#555555", {}}, low{"median - limit x MAD", "#bbbbbb", {}},
        high{"median + limit x MAD", "#bbbbbb", {}};
    for (std::size_t k = 0; k < fleet.units.size(); ++k) {
      const FleetUnit& u = fleet.units[k];
      const auto value = u.values.find(path);
      bool outlying = false;
      for (const auto& o : u.outlying) outlying |= o.first == path;
      p.x.push_back(static_cast<double>(k + 1));
      const double v = value == u.values.end() ? NAN : value->second;
      units.values.push_back(outlying ? NAN : v);
      outliers.values.push_back(outlying ? v : NAN);
      const double m = parameter ? parameter->median : NAN;
      const double spread = parameter ? fleet.outlier_z * parameter->mad : NAN;
      median.values.push_back(m);
      low.values.push_back(m - spread);
      high.values.push_back(m + spread);
    }
    p.series = {units, outliers, median, low, high};
    page->AddPlot(std::move(p));
  }
  page->body() << "</div>\n";
}

void AddUnitSection(const FleetUnit& u, HtmlPage* page) {
  page->body() << "<h3 id=\"" << Anchor(u.unit) << "\">" << Html(u.unit) << "</h3>\n<p>"
               << Html(u.verdict) << " (results in " << Html(u.results_dir) << ")</p>\n"
               << "<table><tr><th class=l>parameter</th><th>value</th><th>standard error</th>"
                  "<th>robust z</th></tr>\n";
  for (const auto& [path, value] : u.values) {
    double z = 0;
    bool outlying = false;
    for (const auto& o : u.outlying) {
      if (o.first == path) outlying = true, z = o.second;
    }
    const auto error = u.standard_errors.find(path);
    page->body() << "<tr" << (outlying ? " class=outlier" : "") << "><td class=l>" << Html(path)
                 << "</td><td>" << Printf("%.6g", value) << "</td><td>"
                 << (error == u.standard_errors.end() ? "" : Printf("%.3g", error->second))
                 << "</td><td>" << (outlying ? Printf("%+.1f", z) : "") << "</td></tr>\n";
  }
  page->body() << "</table>\n";
}

}  // namespace

std::string FleetReportHtml(const FleetSummary& fleet, const ReportOptions& options) {
  CheckOptions(options);
  HtmlPage page(options.title.empty() ? "pneumaid fleet report" : options.title,
                options.max_columns);
  std::ostringstream& body = page.body();
  int outliers = 0;
  for (const FleetUnit& u : fleet.units) outliers += !u.outlying.empty();
  body << "<p>" << fleet.units.size() << " units with a parameter set, " << fleet.failures.size()
       << " failed, " << outliers << " flagged as outliers (robust z-score beyond "
       << Printf("%.3g", fleet.outlier_z) << ": (value - median) / hypot(MAD, the unit's own "
       << "standard error), over the coefficients its fit determined).</p>\n"
       << TextReport(options.text_report) << "<h2>Outliers</h2>\n";
  if (outliers == 0)
    body << "<p>none</p>\n";
  else {
    body << "<table><tr><th class=l>unit</th><th class=l>parameter</th><th>value</th>"
            "<th>fleet median</th><th>robust z</th></tr>\n";
    for (const FleetUnit& u : fleet.units) {
      for (const auto& [path, z] : u.outlying) {
        const FleetParameter* p = FindParameter(fleet, path);
        body << "<tr class=outlier><td class=l><a href=\"#" << Anchor(u.unit) << "\">"
             << Html(u.unit) << "</a></td><td class=l>" << Html(path) << "</td><td>"
             << Printf("%.6g", u.values.at(path)) << "</td><td>"
             << (p ? Printf("%.6g", p->median) : "") << "</td><td>" << Printf("%+.1f", z)
             << "</td></tr>\n";
      }
    }
    body << "</table>\n";
    AddOutlierPlots(fleet, &page);
  }
  body << "<h2>Failures</h2>\n";
  if (fleet.failures.empty())
    body << "<p>none</p>\n";
  else {
    body << "<table><tr><th class=l>unit</th><th class=l>reason</th><th class=l>recorded in</th>"
            "</tr>\n";
    for (const FleetFailure& f : fleet.failures) {
      body << "<tr class=failed><td class=l>" << Html(f.unit) << "</td><td class=l>"
           << Html(f.reason) << "</td><td class=l>" << Html(f.file) << "</td></tr>\n";
    }
    body << "</table>\n";
  }
  body << "<h2>Units</h2>\n<table><tr><th class=l>#</th><th class=l>unit</th>"
          "<th class=l>verdict</th><th class=l>outlying parameters</th></tr>\n";
  for (std::size_t k = 0; k < fleet.units.size(); ++k) {
    const FleetUnit& u = fleet.units[k];
    body << "<tr" << (u.outlying.empty() ? "" : " class=outlier") << "><td class=l>" << k + 1
         << "</td><td class=l><a href=\"#" << Anchor(u.unit) << "\">" << Html(u.unit)
         << "</a></td><td class=l>" << Html(u.verdict) << "</td><td class=l>";
    for (std::size_t i = 0; i < u.outlying.size(); ++i)
      body << (i ? ", " : "") << Html(u.outlying[i].first);
    body << "</td></tr>\n";
  }
  body << "</table>\n<h2>Parameters varying across the fleet</h2>\n<table><tr>"
          "<th class=l>parameter</th><th>median</th><th>MAD (sigma)</th><th>units</th></tr>\n";
  for (const FleetParameter& p : fleet.parameters) {
    if (!(p.mad > 0)) continue;
    body << "<tr><td class=l>" << Html(p.path) << "</td><td>" << Printf("%.6g", p.median)
         << "</td><td>" << Printf("%.3g", p.mad) << "</td><td>" << p.units << "</td></tr>\n";
  }
  body << "</table>\n<h2>Each unit</h2>\n";
  for (const FleetUnit& u : fleet.units) AddUnitSection(u, &page);
  return page.Finish();
}

}  // namespace pneumaid
