#include "pneumaid/ident/valve_fit.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>

#include "pneumaid/model/kvp.h"
#include "valve_branch_fit.h"

namespace pneumaid {
namespace {

using internal::FitBranch;
using internal::kBranchParameters;
using internal::Pack;

// Where q_max poly(u) = q_max inside (low, high], or the middle of the gap:
// the saturation opening that keeps K_vp continuous.
double ContinuousSaturation(const KvpBranchParams& p, double low, double high) {
  const auto excess = [&p](double u) {
    return ((p.a * u + p.b) * u + p.c) * u * u + p.d * u - 1.0;
  };
  if (excess(low) * excess(high) > 0) return 0.5 * (low + high);
  for (int i = 0; i < 60; ++i) {  // bisection: the gap holds one crossing
    const double mid = 0.5 * (low + high);
    (excess(low) * excess(mid) <= 0 ? high : low) = mid;
  }
  return 0.5 * (low + high);
}

// Do the plateaus above `opening` look saturated: each within `flatness`
// (relative) of their mean K_vp?
bool FlatAbove(const std::vector<const ValvePlateau*>& plateaus, double opening, double flatness) {
  double sum = 0;
  int count = 0;
  for (const ValvePlateau* p : plateaus) {
    if (p->u_V > opening) sum += p->kvp_kg_per_s, ++count;
  }
  if (count == 0) return false;
  const double mean = sum / count;
  for (const ValvePlateau* p : plateaus) {
    if (p->u_V > opening && std::fabs(p->kvp_kg_per_s - mean) > flatness * std::fabs(mean))
      return false;
  }
  return true;
}

// A fit at a u_sat read off the log: the search started from the prior (not
// from the split it kept), and u_sat has the standard error `u_sat_error_V`.
void MarkSaturationFitted(const KvpBranchParams& prior, double u_sat_error_V, BranchFit* fit) {
  if (!fit->has_values()) return;
  const auto starts = Pack(prior);
  for (int i = 0; i < kBranchParameters; ++i) fit->coefficients[i].start = starts[i];
  FittedCoefficient& u_sat = fit->coefficients.back();
  u_sat.start = prior.u_sat_V;
  u_sat.held.clear();
  u_sat.standard_error = u_sat_error_V;
  fit->covariance(kBranchParameters, kBranchParameters) = u_sat_error_V * u_sat_error_V;
  fit->u_sat_fitted = true;
}

// The plateaus a fit with u_sat in the gap (low, high) can use: a node of a
// continuous command measures K_vp averaged over its hat, and a hat that
// reaches into the gap mixes the polynomial with K_vp's jump at u_sat.
std::vector<const ValvePlateau*> OutsideGap(const std::vector<const ValvePlateau*>& plateaus,
                                            double low, double high) {
  constexpr double kRoundOff_V = 1e-9;
  std::vector<const ValvePlateau*> outside;
  for (const ValvePlateau* p : plateaus) {
    const double w = p->support_half_width_V;
    if (w > 0 && p->u_V + w > low + kRoundOff_V && p->u_V - w < high - kRoundOff_V) continue;
    outside.push_back(p);
  }
  return outside;
}

// The valve's full opening: the command's top, where u_sat is at the latest.
constexpr double kFullOpening_V = 1.0;

// FitBranch with u_sat free (ValveFitOptions::fit_u_sat).
BranchFit FitBranchAndSaturation(const std::vector<const ValvePlateau*>& plateaus,
                                 const KvpBranchParams& prior, const std::string& prefix,
                                 const ValveFitOptions& options) {
  std::vector<double> openings;
  for (const ValvePlateau* p : plateaus) openings.push_back(p->u_V);
  std::sort(openings.begin(), openings.end());
  // Holds of one nominal level (0.6000 and 0.6003 V) are one opening.
  openings.erase(std::unique(openings.begin(), openings.end(),
                             [&](double a, double b) { return b - a <= options.level_change_V; }),
                 openings.end());
  BranchFit best;
  double gap_low = 0, gap_high = 0;
  const std::size_t saturated = static_cast<std::size_t>(options.min_saturated_openings);
  // Fits u_sat between openings k and k + 1; kept when it beats the best
  // split by more than `margin` in chi-square (Ceres' cost is half of it).
  std::vector<std::pair<std::size_t, double>> split_costs;  // every split fitted: k, cost
  const auto try_split = [&](std::size_t k, double margin) {
    const auto usable = OutsideGap(plateaus, openings[k], openings[k + 1]);
    if (!FlatAbove(usable, openings[k], options.saturation_flatness)) return;
    KvpBranchParams candidate = prior;
    candidate.u_sat_V = 0.5 * (openings[k] + openings[k + 1]);
    const BranchFit fit = FitBranch(usable, candidate, prefix, options);
    if (fit.has_values()) split_costs.emplace_back(k, fit.final_cost);
    if (fit.has_values() &&
        (!best.has_values() || fit.final_cost < best.final_cost - 0.5 * margin)) {
      best = fit;
      gap_low = openings[k];
      gap_high = openings[k + 1];
    }
  };
  for (size_t k = 0; k + saturated < openings.size(); ++k) try_split(k, 0.0);
  // Where the staircase shows saturation, the top opening alone above u_sat
  // competes too: a decreasing branch starts one step below the staircase's
  // top, so a valve saturating between its two highest openings leaves it
  // one saturated plateau, and the split below, whose two top plateaus pass
  // as flat (0.8 and 0.9 V for u_sat 0.83), capped K_vp where it still rises
  // (1.9 % of q_max at 0.78 V on four sweep units).
  // It must fit clearly better (by 9 in chi-square, 3 sigma): on a valve
  // saturated well below the top, noise alone let it win by 0.6.
  constexpr double kClearlyBetterChiSquare = 9.0;
  if (best.has_values() && saturated > 1 && openings.size() >= 2)
    try_split(openings.size() - 2, kClearlyBetterChiSquare);
  if (!best.has_values()) {
    best = FitBranch(plateaus, prior, prefix, options);
    if (best.has_values()) {
      best.coefficients.back().held =
          "the log shows no saturation (no " + std::to_string(saturated) +
          " or more top openings with one flat K_vp); held at the prior's";
    }
    return best;
  }
  // Every split that explains the plateaus within 9 in chi-square of the
  // best (3 sigma) is as good a place for u_sat: where the polynomial has
  // reached q_max to within the noise below the kept split (a staircase of
  // short holds: 0.675 +- 0.014 V reported for 0.75, the polynomial at
  // 0.9993 q_max at 0.7 V), u_sat's interval spans them all. Plateaus only:
  // a continuous command's nodes near the gap differ from split to split.
  const bool plateaus_only =
      std::none_of(plateaus.begin(), plateaus.end(),
                   [](const ValvePlateau* p) { return p->support_half_width_V > 0; });
  double u_sat_low = gap_low, u_sat_high = gap_high;
  for (const auto& [k, cost] : split_costs) {
    if (!plateaus_only || !(cost <= best.final_cost + 0.5 * kClearlyBetterChiSquare)) continue;
    u_sat_low = std::min(u_sat_low, openings[k]);
    u_sat_high = std::max(u_sat_high, openings[k + 1]);
  }
  // Same split, same cost: only the value inside the gap changes.
  KvpBranchParams located = best.params;
  located.u_sat_V = ContinuousSaturation(best.params, gap_low, gap_high);
  best = FitBranch(OutsideGap(plateaus, gap_low, gap_high), located, prefix, options);
  if (best.has_values() && (u_sat_low < gap_low || u_sat_high > gap_high)) {
    char note[200];
    std::snprintf(note, sizeof(note),
                  "u_sat anywhere between %.3g and %.3g V: the splits there explain the "
                  "plateaus within 9 in chi-square of the best",
                  u_sat_low, u_sat_high);
    best.reason += (best.reason.empty() ? "" : "; ") + std::string(note);
  }
  // Saturation seen only at the top of a branch that stops below the full
  // opening may be K_vp still rising slowly above it: when the branch
  // fitted with u_sat one step above its top opening (no plateau saturated,
  // K_vp continuous there) explains the plateaus as well, u_sat's interval
  // reaches to the full opening. (The paper valve's staircase stopped at
  // 0.7 V: 0.65 and 0.7 V within 0.5 % of each other, u_sat 0.675 +- 0.014
  // reported for 0.75.)
  const double top = openings.back();
  if (best.has_values() && openings.size() >= 2 && top < kFullOpening_V - options.level_change_V) {
    KvpBranchParams rising = prior;
    rising.u_sat_V = std::min(kFullOpening_V, 2 * top - openings[openings.size() - 2]);
    const BranchFit above = FitBranch(plateaus, rising, prefix, options);
    if (above.has_values() && above.final_cost < best.final_cost + 0.5 * kClearlyBetterChiSquare) {
      u_sat_high = kFullOpening_V;
      char note[256];
      std::snprintf(note, sizeof(note),
                    "K_vp seen flat only up to the branch's top opening %.3g V is not told from "
                    "K_vp still rising above it: u_sat between %.3g and %.3g V",
                    top, u_sat_low, kFullOpening_V);
      best.reason += (best.reason.empty() ? "" : "; ") + std::string(note);
    }
  }
  MarkSaturationFitted(prior, (u_sat_high - u_sat_low) / std::sqrt(12.0), &best);  // uniform
  best.u_sat_gap_low_V = gap_low;
  best.u_sat_gap_high_V = gap_high;
  return best;
}

// The plateaus of each branch: increasing first, then decreasing.
std::array<std::vector<const ValvePlateau*>, 2> Branches(
    const std::vector<ValvePlateau>& plateaus) {
  std::array<std::vector<const ValvePlateau*>, 2> branches;
  for (const auto& p : plateaus) branches[p.decreasing].push_back(&p);
  return branches;
}

// Where a continuous command's K_vp saturates: the saturation search, which
// leaves out the nodes whose hats span K_vp's jump, picks a gap between nodes
// but cannot tell which of two neighbouring gaps holds a small jump. Of the
// breaks every tenth of a spacing across that gap and the gap either side
// (the other branch's break held), the one whose nodes the branch fits best
// at that u_sat (per degree of freedom: a break next to a grid node leaves
// a limit node with too few samples to report), into breaks->*branch.
// `earlier`: the first reading's plateaus, whose held commands are reused.
void ScanSaturation(const Unit& unit, double normalization, const ValveFitOptions& options,
                    const BranchFit& fit, const std::string& prefix, double KvpBreaks::*branch,
                    const std::vector<ValvePlateau>& earlier, KvpBreaks* breaks) {
  const double width = fit.u_sat_gap_high_V - fit.u_sat_gap_low_V;
  if (!fit.u_sat_fitted || !(width > 0)) return;
  constexpr int kPoints = 30;
  const double low = fit.u_sat_gap_low_V - width, step = 3 * width / kPoints;
  double best = INFINITY, best_V = breaks->*branch;
  for (int j = 0; j < kPoints; ++j) {
    breaks->*branch = low + (j + 0.5) * step;
    if (!(breaks->*branch > 0 && breaks->*branch < 1)) continue;
    const std::vector<ValvePlateau> nodes =
        ExtractValvePlateaus(unit, normalization, options, *breaks, &earlier);
    const auto points = Branches(nodes)[branch == &KvpBreaks::decreasing_V];
    KvpBranchParams at = fit.params;
    at.u_sat_V = breaks->*branch;
    const BranchFit candidate = FitBranch(points, at, prefix, options);
    const double dof = static_cast<double>(points.size()) - kBranchParameters;
    if (!candidate.has_values() || !(dof > 0)) continue;
    if (candidate.final_cost / dof < best)
      best = candidate.final_cost / dof, best_V = breaks->*branch;
  }
  breaks->*branch = best_V;
}

}  // namespace

bool ValveFitOptions::IsValid(std::string* error) const {
  const auto fail = [error](const char* what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (!(settle_fraction >= 0 && settle_fraction < 1))
    return fail("settle_fraction must be in [0, 1)");
  if (min_plateau_samples < 2) return fail("min_plateau_samples must be >= 2");
  if (!(band_sigmas > 0)) return fail("band_sigmas must be > 0");
  if (max_iterations < 1) return fail("max_iterations must be >= 1");
  if (min_saturated_openings < 1) return fail("min_saturated_openings must be >= 1");
  if (!(saturation_flatness > 0)) return fail("saturation_flatness must be > 0");
  if (!(level_change_V > 0)) return fail("level_change_V must be > 0");
  if (max_levels < 2) return fail("max_levels must be >= 2");
  if (!(held_fraction > 0 && held_fraction <= 1)) return fail("held_fraction must be in (0, 1]");
  if (!(node_spacing_V > level_change_V && node_spacing_V <= 0.25))
    return fail("node_spacing_V must be in (level_change_V, 0.25]");
  return true;
}

ValveFitResult FitValve(const Unit& unit, const ValveParams& prior,
                        const ValveFitOptions& options) {
  ValveFitResult result;
  // With u_sat held at the prior's, a continuous command's K_vp may jump there.
  KvpBreaks held;
  if (!options.fit_u_sat) held = {prior.increasing.u_sat_V, prior.decreasing.u_sat_V};
  result.plateaus = ExtractValvePlateaus(unit, prior.normalization, options, held);
  const auto first = Branches(result.plateaus);
  const auto fit = options.fit_u_sat ? FitBranchAndSaturation : FitBranch;
  result.increasing = fit(first[0], prior.increasing, "valve.increasing", options);
  result.decreasing = fit(first[1], prior.decreasing, "valve.decreasing", options);
  // A continuous command's nodes next to u_sat spanned K_vp's jump and were
  // left out of the fit. The log is read again with K_vp free to jump where
  // ScanSaturation finds it, and the branch fitted there from every node.
  const bool nodes = std::any_of(result.plateaus.begin(), result.plateaus.end(),
                                 [](const ValvePlateau& p) { return p.support_half_width_V > 0; });
  if (nodes && (result.increasing.u_sat_fitted || result.decreasing.u_sat_fitted)) {
    KvpBreaks breaks;
    if (result.increasing.u_sat_fitted) breaks.increasing_V = result.increasing.params.u_sat_V;
    if (result.decreasing.u_sat_fitted) breaks.decreasing_V = result.decreasing.params.u_sat_V;
    ScanSaturation(unit, prior.normalization, options, result.increasing, "valve.increasing",
                   &KvpBreaks::increasing_V, result.plateaus, &breaks);
    ScanSaturation(unit, prior.normalization, options, result.decreasing, "valve.decreasing",
                   &KvpBreaks::decreasing_V, result.plateaus, &breaks);
    std::vector<ValvePlateau> again =
        ExtractValvePlateaus(unit, prior.normalization, options, breaks, &result.plateaus);
    const auto second = Branches(again);
    BranchFit refits[2];
    bool all = true;
    for (int b = 0; b < 2; ++b) {
      BranchFit& branch = b == 0 ? result.increasing : result.decreasing;
      if (!branch.u_sat_fitted) continue;
      KvpBranchParams located = branch.params;
      located.u_sat_V = b == 0 ? breaks.increasing_V : breaks.decreasing_V;
      refits[b] =
          FitBranch(second[b], located, b == 0 ? "valve.increasing" : "valve.decreasing", options);
      all = all && refits[b].has_values();
    }
    // Both refits or neither, so that the branches and the plateaus reported agree.
    if (all) {
      for (int b = 0; b < 2; ++b) {
        BranchFit& branch = b == 0 ? result.increasing : result.decreasing;
        if (!branch.u_sat_fitted) continue;
        // u_sat keeps the error of the node gap, now centred on where it lies.
        const double error = branch.coefficients.back().standard_error;
        const double width = branch.u_sat_gap_high_V - branch.u_sat_gap_low_V;
        MarkSaturationFitted(b == 0 ? prior.increasing : prior.decreasing, error, &refits[b]);
        refits[b].u_sat_gap_low_V = refits[b].params.u_sat_V - 0.5 * width;
        refits[b].u_sat_gap_high_V = refits[b].params.u_sat_V + 0.5 * width;
        branch = std::move(refits[b]);
      }
      result.plateaus = std::move(again);
    }
  }
  AppendFit(result.increasing, "increasing", &result);
  AppendFit(result.decreasing, "decreasing", &result);
  return result;
}

std::string ValveFitResult::BriefReport() const {
  std::ostringstream out;
  const auto nodes = std::count_if(plateaus.begin(), plateaus.end(), [](const ValvePlateau& p) {
    return p.support_half_width_V > 0;
  });
  if (!has_values() && plateaus.empty()) {  // not attempted, or no valve log read
    out << "Valve K_vp fit: " << ToString(status) << " (" << reason << ")\n";
    return out.str();
  }
  out << "Valve K_vp fit: " << plateaus.size() - nodes << " plateaus";
  if (nodes > 0) out << ", " << nodes << " nodes of a continuous command";
  out << "\n";
  std::string lag_of;          // each valve log whose meter lag was read off it
  std::set<std::string> said;  // once
  for (const ValvePlateau& p : plateaus) {
    if (!p.meter_lag_read || !said.insert(p.experiment).second) continue;
    char text[160];
    std::snprintf(text, sizeof(text), " %s: %.3g ms%s", p.experiment.c_str(), p.meter_lag_s * 1e3,
                  p.meter_lag_s > 0 ? "" : " (its steps show none)");
    lag_of += text;
  }
  if (!lag_of.empty())
    out << "  the flow meter's lag, which the manifest does not declare, read off the steps:"
        << lag_of << "\n";
  for (const auto& [name, fit] :
       {std::make_pair("increasing", &increasing), std::make_pair("decreasing", &decreasing)}) {
    out << "  " << name << ": " << ToString(fit->status);
    if (!fit->has_values()) {
      out << " (" << fit->reason << ")\n";
      continue;
    }
    char line[256];
    std::snprintf(line, sizeof(line), ", %d %s, cost %.4g -> %.4g in %d iterations\n",
                  fit->plateaus, nodes > 0 ? "plateaus and nodes" : "plateaus", fit->initial_cost,
                  fit->final_cost, fit->iterations);
    out << line;
    if (fit->status == FitStatus::kConverged && !fit->reason.empty())
      out << "    note: " << fit->reason << "\n";
    out << fit->CoefficientReport("    ");
    if (!fit->Correlated(0.95).empty())
      out << "    (the K_vp band is the meaningful uncertainty of poorly separable pairs)\n";
  }
  return out.str();
}

}  // namespace pneumaid
