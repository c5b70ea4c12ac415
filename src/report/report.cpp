#include "pneumaid/report/report.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>

#include "pneumaid/eval/metrics.h"
#include "pneumaid/ident/valve_fit.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/json.h"
#include "pneumaid/model/effects.h"
#include "pneumaid/model/kvp.h"
#include "pneumaid/model/parameter_table.h"
#include "pneumaid/validate/validate.h"
#include "report_page.h"
#include "uplot_assets.h"  // generated from src/report/vendor/uplot by CMake

namespace pneumaid {
namespace {

std::string Html(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else if (c == '&')
      out += "&amp;";
    else if (c == '"')
      out += "&quot;";
    else
      out += c;
  }
  return out;
}

// Numbers for the page's data: 6 significant digits, null for gaps.
void Numbers(std::ostringstream* out, const std::vector<double>& values) {
  *out << "[";
  char text[32];
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i) *out << ",";
    if (!std::isfinite(values[i])) {
      *out << "null";
      continue;
    }
    const auto end =
        std::to_chars(text, text + sizeof(text), values[i], std::chars_format::general, 6);
    out->write(text, end.ptr - text);
  }
  *out << "]";
}

struct Series {
  std::string label, color;
  std::vector<double> values;
  int axis = 1;
  bool points = false;
};

struct Plot {
  std::string id, title, group, x_label, y_label, y2_label;
  std::vector<double> x;
  std::vector<Series> series;
};

// Min/max per column: `columns` buckets of the samples, each giving two
// points (its extremes of every series, the earlier first), so spikes stay.
void Decimate(int columns, Plot* plot) {
  const std::size_t n = plot->x.size();
  if (columns <= 0 || n <= static_cast<std::size_t>(2 * columns)) return;
  std::vector<double> x;
  std::vector<std::vector<double>> values(plot->series.size());
  for (int b = 0; b < columns; ++b) {
    const std::size_t begin = n * b / columns, end = n * (b + 1) / columns;
    if (end <= begin) continue;
    x.push_back(plot->x[begin]);
    x.push_back(plot->x[end - 1]);
    for (std::size_t s = 0; s < plot->series.size(); ++s) {
      const auto& v = plot->series[s].values;
      std::size_t lo = begin, hi = begin;
      for (std::size_t i = begin; i < end; ++i) {
        if (v[i] < v[lo]) lo = i;
        if (v[i] > v[hi]) hi = i;
      }
      values[s].push_back(v[std::min(lo, hi)]);
      values[s].push_back(v[std::max(lo, hi)]);
    }
  }
  plot->x = x;
  for (std::size_t s = 0; s < plot->series.size(); ++s) plot->series[s].values = values[s];
}

void PlotJson(const Plot& p, std::ostringstream* out) {
  *out << "{\"id\":" << JsonString(p.id) << ",\"title\":" << JsonString(p.title)
       << ",\"group\":" << (p.group.empty() ? "null" : JsonString(p.group))
       << ",\"x_label\":" << JsonString(p.x_label) << ",\"y_label\":" << JsonString(p.y_label)
       << ",\"y2_label\":" << JsonString(p.y2_label) << ",\"x\":";
  Numbers(out, p.x);
  *out << ",\"series\":[";
  for (std::size_t s = 0; s < p.series.size(); ++s) {
    const Series& series = p.series[s];
    *out << (s ? "," : "") << "{\"label\":" << JsonString(series.label)
         << ",\"color\":" << JsonString(series.color) << ",\"axis\":" << series.axis
         << ",\"points\":" << (series.points ? "true" : "false") << ",\"values\":";
    Numbers(out, series.values);
    *out << "}";
  }
  *out << "]}";
}

struct ChannelView {
  const char* name;
  std::vector<double> Trajectory::*values;
  const char* unit;
  double scale;   // SI -> display
  double offset;  // added after scaling
};
const ChannelView kViews[] = {{"x", &Trajectory::x_m, "mm", 1e3, 0},
                              {"p1", &Trajectory::p1_Pa, "bar abs", 1e-5, 0},
                              {"p2", &Trajectory::p2_Pa, "bar abs", 1e-5, 0},
                              {"q1", &Trajectory::q1_kg_per_s, "g/s", 1e3, 0},
                              {"q2", &Trajectory::q2_kg_per_s, "g/s", 1e3, 0}};

std::string ParameterTable(const Parameters& params) {
  std::ostringstream out;
  out << "<table><tr><th class=l>parameter</th><th>value</th><th class=l>unit</th>"
         "<th>standard error</th><th class=l>source</th></tr>\n";
  const auto row = [&](const std::string& path, double value, const std::string& unit) {
    const auto error = params.uncertainty.find(path);
    const bool fitted = error != params.uncertainty.end();
    char text[64];
    std::snprintf(text, sizeof(text), "%.6g", value);
    out << "<tr" << (fitted ? "" : " class=prior") << "><td class=l>" << Html(path) << "</td><td>"
        << text << "</td><td class=l>" << Html(unit) << "</td><td>";
    if (fitted) {
      std::snprintf(text, sizeof(text), "%.3g", error->second);
      out << text;
    }
    out << "</td><td class=l>" << (fitted ? "fitted" : "prior / given") << "</td></tr>\n";
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

}  // namespace

bool ReportOptions::IsValid(std::string* error) const {
  if (max_columns < 10) {
    if (error != nullptr) *error = "max_columns must be >= 10";
    return false;
  }
  return true;
}

std::string UnitReportHtml(const Parameters& params, const Unit& unit,
                           const ReportOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) throw InputError("report options", 0, 0, error);
  const std::string title =
      options.title.empty() ? "pneumaid report: " + unit.manifest.unit : options.title;
  std::vector<Plot> plots;
  std::ostringstream body;
  body << "<h1>" << Html(title) << "</h1>\n<div id=\"pneumaid-status\">checking</div>\n"
       << "<p class=note>Unit directory " << Html(unit.directory) << "; parameter set of unit "
       << Html(params.unit) << ". Provenance: " << Html(params.provenance_yaml) << "</p>\n"
       << "<h2>Parameters</h2>\n<p class=note>SI units, pressures absolute; grey rows come from "
          "the prior or the rig, not from a fit.</p>\n"
       << ParameterTable(params);
  // Every simulable run: the metrics table; the validation runs: plots.
  ValidationOptions v;
  for (const Experiment& e : unit.experiments) {
    if (IsSimulable(e.entry.kind)) v.experiment_ids.push_back(e.entry.id);
  }
  if (!v.experiment_ids.empty()) {
    const ValidationReport report = ValidateUnit(params, unit, v);
    body << "<h2>Runs: measured against simulated</h2>\n<table><tr><th class=l>run</th>"
            "<th class=l>channel</th><th>RMSE</th><th>max |error|</th><th>fit %</th></tr>\n";
    for (const ExperimentValidation& e : report.experiments) {
      for (const ChannelView& view : kViews) {
        const auto m = e.channels.find(view.name);
        if (m == e.channels.end()) continue;
        char line[200];
        std::snprintf(
            line, sizeof(line), "<td>%.4g %s</td><td>%.4g %s</td><td>%s</td>",
            m->second.rmse * view.scale, view.unit, m->second.max_abs * view.scale, view.unit,
            m->second.nrmse_fit_percent ? FormatSignificant(*m->second.nrmse_fit_percent, 4).c_str()
                                        : "-");
        body << "<tr><td class=l>" << Html(e.id) << "</td><td class=l>" << view.name << "</td>"
             << line << "</tr>\n";
      }
    }
    body << "</table>\n";
    for (const ExperimentValidation& e : report.experiments) {
      const Experiment* logged = nullptr;
      for (const Experiment& x : unit.experiments) logged = x.entry.id == e.id ? &x : logged;
      if (logged == nullptr || logged->entry.kind != ExperimentKind::kValidation) continue;
      if (!e.simulation.ok()) {
        body << "<p>" << Html(e.id) << ": simulation failed: " << Html(e.simulation.message)
             << "</p>\n";
        continue;
      }
      body << "<h3>" << Html(e.id) << "</h3>\n<div class=plots>";
      for (const ChannelView& view : kViews) {
        const auto& measured = e.measured.*(view.values);
        const auto& simulated = e.simulated.*(view.values);
        if (measured.empty() || simulated.size() != measured.size()) continue;
        Plot p;
        p.id = "plot" + std::to_string(plots.size());
        p.title = e.id + ": " + view.name;
        p.group = "run-" + e.id;
        p.x_label = "t [s]";
        p.y_label = std::string(view.name) + " [" + view.unit + "]";
        p.y2_label = "measured - simulated [" + std::string(view.unit) + "]";
        p.x = e.measured.t_s;
        // The difference first: drawn underneath, light, on its own axis.
        Series d{"measured - simulated", "#c8c8c8", {}, 2}, m{"measured", "#1f77b4", {}},
            s{"simulated", "#d62728", {}};
        for (std::size_t i = 0; i < measured.size(); ++i) {
          m.values.push_back(measured[i] * view.scale + view.offset);
          s.values.push_back(simulated[i] * view.scale + view.offset);
          d.values.push_back((measured[i] - simulated[i]) * view.scale);
        }
        p.series = {d, m, s};
        Decimate(options.max_columns, &p);
        body << "<div id=\"" << p.id << "\"></div>";
        plots.push_back(std::move(p));
      }
      body << "</div>\n";
    }
  }
  // The valve gain (seed paper Fig. 3): plateaus and both fitted branches.
  const std::vector<ValvePlateau> plateaus =
      ExtractValvePlateaus(unit, params.valve.normalization, ValveFitOptions{});
  if (!plateaus.empty()) {
    Plot p;
    p.id = "plot" + std::to_string(plots.size());
    p.title = "valve gain K_vp: plateaus and fitted branches";
    p.x_label = "u [V]";
    p.y_label = "K_vp [g/s]";
    std::set<double> xs;
    for (int k = 0; k <= 100; ++k) xs.insert(k / 100.0);
    for (const ValvePlateau& plateau : plateaus) xs.insert(plateau.u_V);
    p.x.assign(xs.begin(), xs.end());
    const auto inc = MakeKvpCoefficients<double>(params.valve.increasing);
    const auto dec = MakeKvpCoefficients<double>(params.valve.decreasing);
    Series up{"increasing branch", "#1f77b4", {}}, down{"decreasing branch", "#d62728", {}};
    Series up_points{"plateaus (opening)", "#1f77b4", {}, 1, true},
        down_points{"plateaus (closing)", "#d62728", {}, 1, true};
    for (double u : p.x) {
      const bool grid = std::fabs(u * 100 - std::round(u * 100)) < 1e-9;
      up.values.push_back(grid ? 1e3 * Kvp(u, inc) : NAN);
      down.values.push_back(grid ? 1e3 * Kvp(u, dec) : NAN);
      double a = NAN, b = NAN;
      for (const ValvePlateau& plateau : plateaus) {
        if (plateau.u_V != u) continue;
        (plateau.decreasing ? b : a) = 1e3 * plateau.kvp_kg_per_s;
      }
      up_points.values.push_back(a);
      down_points.values.push_back(b);
    }
    p.series = {up, down, up_points, down_points};
    body << "<h2>Valve gain</h2>\n<div class=plots><div id=\"" << p.id << "\"></div></div>\n";
    plots.push_back(std::move(p));
  }
  // The tube's step responses (seed paper Figs. 6 and 7): the meters'
  // readings and q_out predicted from q_in through the fitted lag at that
  // length (both meters' own lags are the same filter, so they commute).
  bool tube_heading = false;
  for (const Experiment& e : unit.experiments) {
    if (e.entry.kind != ExperimentKind::kPipeline) continue;
    const double length = e.entry.tube_length_m.value_or(params.pipeline.tube_length_m);
    double delta = params.pipeline.delta_per_s;
    for (const DeltaAtLength& at : params.pipeline.delta_by_length) {
      if (std::fabs(at.tube_length_m - length) < 1e-9) delta = at.delta_per_s;
    }
    Plot p;
    p.id = "plot" + std::to_string(plots.size());
    char title[160];
    std::snprintf(title, sizeof(title), "%s: tube %.2f m, delta %.3g 1/s", e.entry.id.c_str(),
                  length, delta);
    p.title = title;
    p.x_label = "t [s]";
    p.y_label = "mass flow [g/s]";
    p.x = e.column("t");
    const auto& in = e.column("q_in");
    const auto& out = e.column("q_out");
    if (p.x.empty() || in.size() != p.x.size() || out.size() != p.x.size()) continue;
    const std::vector<double> predicted = FirstOrderLag(p.x, in, 1.0 / delta);
    Series a{"q_in measured", "#1f77b4", {}}, b{"q_out measured", "#2ca02c", {}},
        c{"q_out through the fitted lag", "#d62728", {}};
    for (std::size_t i = 0; i < p.x.size(); ++i) {
      a.values.push_back(in[i] * 1e3);
      b.values.push_back(out[i] * 1e3);
      c.values.push_back(predicted[i] * 1e3);
    }
    p.series = {a, b, c};
    Decimate(options.max_columns, &p);
    if (!tube_heading) body << "<h2>Tube step responses</h2>\n<div class=plots>";
    tube_heading = true;
    body << "<div id=\"" << p.id << "\"></div>";
    plots.push_back(std::move(p));
  }
  if (tube_heading) body << "</div>\n";
  std::ostringstream data;
  data << "var PNEUMAID_DATA = {\"plots\":[";
  for (std::size_t k = 0; k < plots.size(); ++k) {
    if (k) data << ",\n";
    PlotJson(plots[k], &data);
  }
  data << "]};\n";
  std::ostringstream page;
  page << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>"
       << Html(title) << "</title>\n<style>" << report_internal::kUplotCss
       << report_internal::kPageStyle << "</style>\n<script>" << report_internal::kUplotJs
       << "</script>\n</head><body>\n"
       << body.str() << "<p class=note>Plots: uPlot " << report_internal::kUplotVersion
       << " (MIT licence, embedded). Long runs are shown with the minimum and maximum of each "
          "of "
       << options.max_columns << " columns.</p>\n<script>" << data.str()
       << report_internal::kPageScript << "</script>\n</body></html>\n";
  return page.str();
}

}  // namespace pneumaid
