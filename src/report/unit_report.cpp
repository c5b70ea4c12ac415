// A unit's page: parameters, run metrics, measured against simulated runs,
// and the seed paper's component plots read off the unit's own logs.
#include <algorithm>
#include <cmath>
#include <set>

#include "html_page.h"
#include "pneumaid/eval/metrics.h"
#include "pneumaid/ident/friction_fit.h"
#include "pneumaid/ident/valve_fit.h"
#include "pneumaid/model/friction.h"
#include "pneumaid/model/kvp.h"
#include "pneumaid/report/report.h"
#include "report_sections.h"

namespace pneumaid {
namespace {

using namespace report_internal;

// Per validation run (every run without any) one plot per channel: measured, simulated and their
// difference (on its own axis), one run's plots sharing their time axis.
void AddRunPlots(const ValidationReport& report, const Unit& unit, HtmlPage* page) {
  for (const ExperimentValidation* e : RunsToPlot(report, unit)) {
    if (!e->simulation.ok()) continue;
    page->body() << "<h3>" << Html(e->id) << "</h3>\n<div class=plots>";
    for (const ChannelView& view : kChannelViews) {
      const auto& measured = e->measured.*(view.values);
      const auto& simulated = e->simulated.*(view.values);
      if (measured.empty() || simulated.size() != measured.size()) continue;
      Plot p;
      p.title = e->id + ": " + view.name;
      p.group = "run-" + e->id;
      p.x_label = "t [s]";
      p.y_label = std::string(view.name) + " [" + view.unit + "]";
      p.y2_label = "measured - simulated [" + std::string(view.unit) + "]";
      p.x = e->measured.t_s;
      // The difference first: drawn underneath, light, on its own axis.
      Series d{"measured - simulated", "#c8c8c8", {}, 2}, m{"measured", "#1f77b4", {}},
          s{"simulated", "#d62728", {}};
      for (std::size_t i = 0; i < measured.size(); ++i) {
        m.values.push_back(measured[i] * view.scale);
        s.values.push_back(simulated[i] * view.scale);
        d.values.push_back((measured[i] - simulated[i]) * view.scale);
      }
      p.series = {d, m, s};
      page->AddPlot(std::move(p));
    }
    page->body() << "</div>\n";
  }
}

// The valve gain (seed paper Fig. 3): the set's branches against the
// measured plateaus, and the band (2 standard errors) of each branch as the
// unit's staircase alone determines it (the valve fit on these logs): a set
// from identify lies on its middle, a refined or a prior set shows where it
// leaves what the staircase says.
void AddValveGain(const Parameters& params, const Unit& unit, HtmlPage* page) {
  const ValveFitResult fit = FitValve(unit, params.valve, ValveFitOptions{});
  const std::vector<ValvePlateau>& plateaus = fit.plateaus;
  if (plateaus.empty()) return;
  Plot p;
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
  // The bands on the same grid (the fit's grid: every hundredth of a volt).
  std::vector<Series> bands;
  for (const BranchFit* branch : {&fit.increasing, &fit.decreasing}) {
    if (branch->band.u_V.empty()) continue;
    const std::string name = branch == &fit.increasing ? "opening" : "closing";
    Series lower{"staircase fit, " + name + " - 2 SE", "#9ab", {}},
        upper{"staircase fit, " + name + " + 2 SE", "#9ab", {}};
    for (double u : p.x) {
      double a = NAN, b = NAN;
      for (std::size_t k = 0; k < branch->band.u_V.size(); ++k) {
        if (std::fabs(branch->band.u_V[k] - u) > 1e-9) continue;
        a = 1e3 * branch->band.lower[k];
        b = 1e3 * branch->band.upper[k];
      }
      lower.values.push_back(a);
      upper.values.push_back(b);
    }
    bands.push_back(lower);
    bands.push_back(upper);
  }
  p.series = {up, down, up_points, down_points};
  p.series.insert(p.series.end(), bands.begin(), bands.end());
  page->body() << "<h2>Valve gain</h2>\n<p class=note>Lines: the set's two branches. Points: "
                  "the plateaus of the staircase. Thin lines: the band (2 standard errors) of "
                  "each branch fitted to this staircase alone.</p>\n<div class=plots>";
  page->AddPlot(std::move(p));
  page->body() << "</div>\n";
}

// The friction-velocity map (seed paper Figs. 8 and 9): per direction the
// force balance of the smoothly sliding samples and the fitted Stribeck
// curve, when the unit has stroke logs. At most `max_points` samples per
// direction are shown (evenly picked); the curve spans the speeds seen.
void AddFrictionMap(const Parameters& params, const Unit& unit, int max_points, HtmlPage* page) {
  if (std::none_of(unit.experiments.begin(), unit.experiments.end(),
                   [](const Experiment& e) { return e.entry.kind == ExperimentKind::kStroke; }))
    return;
  const std::vector<FrictionMapSample> map = FrictionVelocityMap(unit, FrictionFitOptions{});
  page->body() << "<h2>Friction against velocity</h2>\n<p class=note>Points: the force balance "
                  "F - M a of smoothly sliding samples of the stroke logs (v and a by a local "
                  "quadratic over 10 ms). Line: the parameter set's Stribeck curve.</p>\n"
                  "<div class=plots>";
  for (const int direction : {+1, -1}) {
    std::vector<const FrictionMapSample*> samples;
    double top = 0;
    for (const FrictionMapSample& s : map) {
      if (s.direction != direction) continue;
      samples.push_back(&s);
      top = std::max(top, s.speed_m_per_s);
    }
    const StribeckParams& fitted =
        direction > 0 ? params.friction.positive : params.friction.negative;
    const auto c = MakeStribeckCoefficients<double>(fitted);
    Plot p;
    p.title = direction > 0 ? "friction, extending (v > 0)" : "friction, retracting (v < 0)";
    if (samples.empty()) {
      // The curve alone, over the Stribeck drop and beyond.
      p.title += ": no smooth slide logged";
      top = std::max(5 * fitted.stribeck_velocity_m_per_s, 0.05);
    }
    p.x_label = "|v| [mm/s]";
    p.y_label = "friction [N]";
    // Points and curve on one sorted x: the curve at 200 speeds, the points
    // at theirs, NaN where a series has no value.
    const std::size_t step = std::max<std::size_t>(1, samples.size() / max_points);
    std::vector<std::pair<double, double>> points;
    for (std::size_t i = 0; i < samples.size(); i += step)
      points.push_back({samples[i]->speed_m_per_s, samples[i]->friction_N});
    const int curve = 200;
    for (int k = 0; k <= curve; ++k) points.push_back({top * k / curve, NAN});
    std::sort(points.begin(), points.end(), [](const auto& a, const auto& b) {
      return a.first < b.first ||
             (a.first == b.first && std::isnan(a.second) < std::isnan(b.second));
    });
    Series measured{"force balance", "#1f77b4", {}, 1, true},
        model{"Stribeck curve", "#d62728", {}};
    for (const auto& [v, f] : points) {
      p.x.push_back(v * 1e3);
      measured.values.push_back(f);
      model.values.push_back(std::isnan(f) ? StribeckMagnitude(v, c) : NAN);
    }
    p.series = {measured, model};
    page->AddPlot(std::move(p));
  }
  page->body() << "</div>\n";
}

// The tube's step responses (seed paper Figs. 6 and 7): the meters' readings
// and q_out predicted from q_in through the fitted lag at that length (both
// meters' own lags are the same filter, so they commute).
void AddTubeResponses(const Parameters& params, const Unit& unit, HtmlPage* page) {
  bool heading = false;
  for (const Experiment& e : unit.experiments) {
    if (e.entry.kind != ExperimentKind::kPipeline) continue;
    const double length = e.entry.tube_length_m.value_or(params.pipeline.tube_length_m);
    double delta = params.pipeline.delta_per_s;
    for (const DeltaAtLength& at : params.pipeline.delta_by_length) {
      if (std::fabs(at.tube_length_m - length) < 1e-9) delta = at.delta_per_s;
    }
    Plot p;
    p.title = Printf("%s: tube %.2f m, delta %.3g 1/s", e.entry.id.c_str(), length, delta);
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
    if (!heading) page->body() << "<h2>Tube step responses</h2>\n<div class=plots>";
    heading = true;
    page->AddPlot(std::move(p));
  }
  if (heading) page->body() << "</div>\n";
}

}  // namespace

std::string UnitReportHtml(const Parameters& params, const Unit& unit, const ReportOptions& options,
                           const ValidationReport* simulated) {
  report_internal::CheckOptions(options);
  HtmlPage page(options.title.empty() ? "pneumaid report: " + unit.manifest.unit : options.title,
                options.max_columns);
  page.body() << "<p class=note>Unit directory " << Html(unit.directory)
              << "; parameter set of unit " << Html(params.unit)
              << ". Provenance: " << Html(params.provenance_yaml) << "</p>\n"
              << TextReport(options.text_report)
              << "<h2>Parameters</h2>\n<p class=note>SI units, pressures absolute; grey rows "
                 "come from the prior or the rig, not from a fit.</p>\n"
              << ParameterTable(params);
  ValidationOptions v;
  v.experiment_ids = SimulableRuns(unit);
  if (simulated != nullptr || !v.experiment_ids.empty()) {
    const ValidationReport report =
        simulated != nullptr ? *simulated : ValidateUnit(params, unit, v);
    page.body() << "<h2>Runs: measured against simulated</h2>\n" << MetricsTable(report);
    AddRunPlots(report, unit, &page);
  }
  AddValveGain(params, unit, &page);
  AddFrictionMap(params, unit, options.max_columns, &page);
  AddTubeResponses(params, unit, &page);
  return page.Finish();
}

}  // namespace pneumaid
