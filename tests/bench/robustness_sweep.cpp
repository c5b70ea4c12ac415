// Issue 12's robustness sweep: N seeded synthetic units whose truths,
// protocols and model mismatch are drawn across the ranges a fleet of real
// rigs covers, each identified (`identify`), refined (`configs/fit-default.yaml`,
// as `identify --refine`) and validated on its held-out runs; per coefficient
// the share of units within the tolerance, the held-out rule, the
// honesty of the standard errors, and the median times.
//
//   robustness_sweep N [--seed S] [--jobs J] [--min-units K] [--keep DIR]
//                    [--min-friction-total K]
//                    [--min-units-valve-tube K]
//                    [--start-prior on|off] [--start identify|truth|rig]
//                    [--held-out-probe K] [--error-blocks S]
//                    [--cost-resolution-directions K] [--relative-tolerance R]
//                    [--units I,J,...] [--stick-creep on|off] [--rig-creep V]
//                    [--clock-jitter J]
//
// Every unit is synthetic (pneumaid's synthetic rig, drawn from the seed),
// not measured. --min-units K: exit 1 unless every coefficient is within
// tolerance on at least K units (issue 12's suite target: 6 units, K = 5;
// scripts/test.sh gates on 4, docs/identification.md); --min-units-valve-tube
// K: the same for K_vp and delta only; --min-friction-total K: exit 1 unless
// at least K of the units' friction coefficients (8 per unit) are within
// tolerance. --start truth: refine from the
// true parameters instead of identify's (how far starts are the gap).
// --start rig: refine the rig's own model from the truth: where the rig
// creeps (its smooth stick), the truth with that creep as `stick_creep` and
// its v freed over the catalog's plausible range, so model and rig agree;
// what the logs determine (the held-out rule then measures against that
// model's runs).
// --held-out-probe K: per unit, K friction sets drawn within half the
// issue's tolerances around the truth (all else true) are validated on the
// held-out runs: how many pass the held-out rule (is that rule consistent
// with the tolerances on this unit?). --error-blocks S and
// --cost-resolution-directions K set the refinement's options of those names
// (RefineOptions::clustered_error_block_s, cost_resolution_directions; 0:
// off), to measure what they give; --relative-tolerance R the fits'
// simulations' (RefineOptions::simulation.relative_tolerance, 1e-5 by
// default). --units I,J: only those units of the N
// (each unit's draw depends on the seed and its index alone).
// --clock-jitter J: every unit's logger keeps no time, each interval the
// nominal one times 1 + U(-J, J) (Protocol::clock_jitter; the other draws
// unchanged).
// --stick-creep off: the refinement without its creep fit
// (RefineOptions::fit_stick_creep, on as in `identify --refine`).
// --rig-creep V: every unit's rig sticks by the smooth law with creep speed
// V [m/s] (the draw's other values unchanged): a rig regularised wider than
// the sweep draws.
// --hidden effects.NAME.PARAM=VALUE (repeatable): every unit's rig has that
// effect of the catalog (docs/effects.md), which the fitted model lacks: a
// rig's physics the paper leaves out (a heat exchange, a valve's lag, a leak).
#include <glog/logging.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <mutex>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <tuple>
#include <vector>

#include "../ident/kvp_test_util.h"
#include "pneumaid/ident/identify.h"
#include "pneumaid/ident/refine.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/rig_writer.h"
#include "pneumaid/model/effects.h"
#include "pneumaid/model/kvp.h"
#include "pneumaid/model/parameter_table.h"
#include "pneumaid/synth/synthetic_rig.h"
#include "pneumaid/validate/validate.h"
#include "sweep_draw.h"

namespace pneumaid {
namespace {

using sweep::Draw;
using sweep::FrictionLine;
using sweep::MakeDraw;
using sweep::Uniform;

const std::string kSource = PNEUMAID_SOURCE_DIR;

// The names of the checked coefficients, in the table's order.
const std::vector<std::string> kChecked = {"kvp.increasing", "kvp.decreasing", "delta",  "pos.Fs",
                                           "pos.Fd",         "pos.b",          "pos.vs", "neg.Fs",
                                           "neg.Fd",         "neg.b",          "neg.vs"};

// Largest |K_vp fitted - true| / q_max over u in [0, 1], outside the
// staircase's gap that holds the true u_sat (no plateau tells where the
// polynomial ends there: docs/identification.md).
double KvpError(const KvpBranchParams& fit, const KvpBranchParams& real, double step_V) {
  const double gap_high = std::ceil(real.u_sat_V / step_V - 1e-9) * step_V;
  return testing::WorstKvpError(fit, real, gap_high - step_V, gap_high);
}

bool Within(double value, double truth, double fraction, double floor) {
  return std::fabs(value - truth) <= std::max(fraction * std::fabs(truth), floor);
}

// The friction tolerances: within `fraction` of the truth or
// `floor` (SI), whichever is larger; `lowest`, the smallest physical value.
struct FrictionTolerance {
  const char* name;
  double StribeckParams::*member;
  double fraction, floor, lowest;
};
const FrictionTolerance kFrictionTolerances[] = {
    {"Fs", &StribeckParams::static_force_N, 0.05, 0.1, 0},
    {"Fd", &StribeckParams::dynamic_force_N, 0.05, 0.1, 0},
    {"b", &StribeckParams::viscous_N_s_per_m, 0.15, 0.5, 0},
    {"vs", &StribeckParams::stribeck_velocity_m_per_s, 0.25, 1e-3, 1e-4}};

// Per checked coefficient: is `fit` within the tolerance of `t`?
std::map<std::string, bool> Check(const Parameters& fit, const Parameters& t, double step_V) {
  std::map<std::string, bool> ok;
  ok["kvp.increasing"] = KvpError(fit.valve.increasing, t.valve.increasing, step_V) <= 0.01;
  ok["kvp.decreasing"] = KvpError(fit.valve.decreasing, t.valve.decreasing, step_V) <= 0.01;
  ok["delta"] = Within(fit.pipeline.delta_per_s, t.pipeline.delta_per_s, 0.05, 0);
  for (const auto& [prefix, f, real] :
       {std::make_tuple("pos.", &fit.friction.positive, &t.friction.positive),
        std::make_tuple("neg.", &fit.friction.negative, &t.friction.negative)}) {
    for (const FrictionTolerance& c : kFrictionTolerances)
      ok[std::string(prefix) + c.name] = Within(f->*c.member, real->*c.member, c.fraction, c.floor);
  }
  return ok;
}

// The held-out rule: every validation run's x RMSE with `fit` at
// most twice the truth's plus 0.05 mm. The worst run (by its share of its
// limit) into worst_mm and limit_mm.
bool HeldOutRule(const ValidationReport& at_truth, const ValidationReport& at_fit, double* worst_mm,
                 double* limit_mm) {
  bool ok = true;
  for (std::size_t k = 0; k < at_fit.experiments.size(); ++k) {
    const double got = at_fit.experiments[k].channels.at("x").rmse;
    const double limit = 2 * at_truth.experiments[k].channels.at("x").rmse + 0.05e-3;
    if (k == 0 || got / limit > *worst_mm / std::max(*limit_mm, 1e-12)) {
      *worst_mm = got * 1e3;
      *limit_mm = limit * 1e3;
    }
    ok = ok && got <= limit;
  }
  return ok;
}

// How consistent the held-out rule is with the coefficient tolerances:
// `sets` friction sets, each coefficient drawn uniformly within
// `fraction` of its tolerance around the truth (everything else true),
// validated on the held-out runs; how many pass the rule.
int HeldOutProbe(const Parameters& truth, const Unit& unit, const ValidationOptions& v,
                 const ValidationReport& at_truth, int sets, double fraction, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  int pass = 0;
  for (int s = 0; s < sets; ++s) {
    Parameters p = truth;
    for (StribeckParams* f : {&p.friction.positive, &p.friction.negative}) {
      for (const FrictionTolerance& c : kFrictionTolerances) {
        const double t = f->*c.member, w = fraction * std::max(c.fraction * t, c.floor);
        f->*c.member = std::max(c.lowest, Uniform(&rng, t - w, t + w));
      }
    }
    double worst = 0, limit = 0;
    pass += HeldOutRule(at_truth, ValidateUnit(p, unit, v), &worst, &limit);
  }
  return pass;
}

// How honest a fit's standard errors are: of the coefficients checked, how
// many lie within 3 and within 1 standard error of the truth, and those
// farther than 3: path (z: value, truth, se).
struct ErrorCoverage {
  int checked = 0, within_3 = 0, within_1 = 0;
  std::string outside_3;

  void Add(const std::string& path, double value, double truth, double standard_error) {
    if (!(standard_error > 0)) return;
    ++checked;
    const double z = std::fabs(value - truth) / standard_error;
    within_3 += z <= 3;
    within_1 += z <= 1;
    if (z > 3) {
      char item[160];
      std::snprintf(item, sizeof(item), " %s (%.3g: %.4g, truth %.4g, se %.2g)", path.c_str(), z,
                    value, truth, standard_error);
      outside_3 += item;
    }
  }
  void Add(const ErrorCoverage& other) {
    checked += other.checked;
    within_3 += other.within_3;
    within_1 += other.within_1;
  }
};

struct UnitResult {
  std::string id, summary, status;
  std::string friction;  // identified and refined friction, one line
  bool explained = false;
  std::map<std::string, bool> ok, identify_ok;  // after refinement, after identify
  double chi_square = NAN, truth_chi_square = NAN, identify_s = 0, refine_s = 0;
  double held_out_mm = 0, held_out_limit_mm = 0;  // worst validation run, and its limit
  bool held_out_ok = false;
  int probe_pass = -1;  // --held-out-probe: friction sets that pass the rule
  ErrorCoverage refined_errors, identify_errors;  // the refined coefficients' paths
  std::string failure;
};

// Where the refinement starts (--start).
enum class Start { kIdentify, kTruth, kRig };

UnitResult RunUnit(std::uint64_t seed, int index, const std::filesystem::path& scratch, bool keep,
                   const RefineOptions& refine_options, Start start, int probe_sets,
                   double rig_creep_m_per_s, double clock_jitter,
                   const std::map<std::string, double>& hidden) {
  UnitResult out;
  char id[32];
  std::snprintf(id, sizeof(id), "sweep-%02d", index);
  out.id = id;
  Draw d = MakeDraw(seed, index);
  if (rig_creep_m_per_s > 0) {
    d.protocol.mismatch.regularized_friction = true;
    d.protocol.mismatch.stick_velocity_m_per_s = rig_creep_m_per_s;
    char creep[48];
    std::snprintf(creep, sizeof(creep), " (rig creep %.2g m/s)", rig_creep_m_per_s);
    d.summary += creep;
  }
  if (clock_jitter > 0) {
    d.protocol.clock_jitter = clock_jitter;
    char clock[48];
    std::snprintf(clock, sizeof(clock), " (clock +-%.0f %%)", 100 * clock_jitter);
    d.summary += clock;
  }
  for (const auto& [path, value] : hidden) {
    std::string name, parameter;
    SplitEffectPath(path, &name, &parameter);
    d.truth.effects[name][parameter] = value;
    d.summary += " (hidden " + path + " " + FormatDouble(value) + ")";
  }
  out.summary = d.summary;
  try {
    const std::filesystem::path dir = scratch / id;
    std::filesystem::remove_all(dir);
    WriteDirectoryAtomically(dir.string(),
                             UnitFiles(Synthesize(d.truth, d.protocol, seed + index, id)));
    const Unit unit = ReadUnit(dir.string());
    const Parameters prior = LoadParams(kSource + "/configs/paper.yaml");
    IdentifyReport report;
    auto clock = std::chrono::steady_clock::now();
    const Parameters identified = Identify(unit, prior, IdentifyOptions{}, &report);
    out.identify_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - clock).count();
    clock = std::chrono::steady_clock::now();
    const FitSpec spec = LoadFitSpec(kSource + "/configs/fit-default.yaml");
    Parameters from = start == Start::kIdentify ? identified : d.truth;
    FitSpec refine_spec = spec;
    if (start == Start::kRig && d.protocol.mismatch.regularized_friction) {
      from.effects["stick_creep"]["v"] = d.protocol.mismatch.stick_velocity_m_per_s;
      const EffectParameterInfo& v = *FindEffectParameter("effects.stick_creep.v");
      refine_spec.parameters.push_back(
          {"effects.stick_creep.v", v.plausible_min, v.plausible_max, ParameterScale::kLog});
    }
    // From the truth (or the rig's model) the start is no measurement: the
    // refined set is judged whatever its verdict.
    RefineOptions options = refine_options;
    options.write_start_unless_explained &= start == Start::kIdentify;
    const RefineResult refined = Refine(from, unit, refine_spec, options);
    out.refine_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - clock).count();
    // The truth the fit is judged by; with --start rig, the rig's own model.
    const Parameters& t = start == Start::kRig ? from : d.truth;
    out.truth_chi_square = EvaluateFit(t, unit, spec, refine_options).reduced_chi_square;
    out.status = ToString(refined.status);
    out.explained = refined.status == FitStatus::kConverged;
    out.chi_square = refined.reduced_chi_square;
    const Parameters& fit = refined.has_values() ? refined.params : identified;
    out.ok = Check(fit, d.truth, d.staircase_step_V);
    out.identify_ok = Check(identified, d.truth, d.staircase_step_V);
    out.friction = "identify " + FrictionLine(identified.friction) + ", refine " +
                   FrictionLine(fit.friction) +
                   (refined.screen_report.empty() ? "" : "\n  " + refined.screen_report) +
                   (refined.coordinate_report.empty() ? "" : "\n  " + refined.coordinate_report) +
                   (refined.velocity_report.empty() ? "" : "\n  " + refined.velocity_report) +
                   (refined.robust_report.empty() ? "" : "\n  " + refined.robust_report) +
                   (refined.windowed_report.empty() ? "" : "\n  " + refined.windowed_report) +
                   (refined.polish_report.empty() ? "" : "\n  " + refined.polish_report) +
                   (refined.rounds_report.empty() ? "" : "\n  " + refined.rounds_report) +
                   (refined.creep_report.empty() ? "" : "\n  " + refined.CreepLine());
    for (const FittedCoefficient& rp : refined.coefficients) {
      double truth = 0, value = 0;
      if (!GetParameter(t, rp.path, &truth)) continue;
      // As written: the start's value and error where the model does not
      // explain the runs (RefineResult::start_written).
      double written = rp.value, written_error = rp.standard_error;
      if (refined.start_written) {
        GetParameter(fit, rp.path, &written);
        const auto found = fit.uncertainty.find(rp.path);
        written_error = found == fit.uncertainty.end() ? 0 : found->second;
      }
      out.refined_errors.Add(rp.path, written, truth, written_error);
      const auto error = identified.uncertainty.find(rp.path);
      if (error != identified.uncertainty.end() && GetParameter(identified, rp.path, &value))
        out.identify_errors.Add(rp.path, value, truth, error->second);
    }
    ValidationOptions v;
    for (const auto& e : unit.experiments)
      if (e.entry.kind == ExperimentKind::kValidation) v.experiment_ids.push_back(e.entry.id);
    const ValidationReport at_truth = ValidateUnit(t, unit, v), at_fit = ValidateUnit(fit, unit, v);
    out.held_out_ok = HeldOutRule(at_truth, at_fit, &out.held_out_mm, &out.held_out_limit_mm);
    if (probe_sets > 0) {
      out.probe_pass = HeldOutProbe(t, unit, v, at_truth, probe_sets, 0.5, seed + index);
    }
    if (!keep) std::filesystem::remove_all(dir);
  } catch (const std::exception& e) {
    out.failure = e.what();
  }
  return out;
}

double Median(std::vector<double> v) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

}  // namespace
}  // namespace pneumaid

int main(int argc, char** argv) {
  using namespace pneumaid;
  FLAGS_minloglevel = google::GLOG_FATAL;  // as the CLI (src/cli/main.cpp)
  if (argc < 2) {
    std::cerr << "usage: robustness_sweep N [--seed S] [--jobs J] [--min-units K] "
                 "[--min-units-valve-tube K] [--min-friction-total K] [--keep DIR] "
                 "[--start-prior on|off] "
                 "[--start identify|truth|rig] [--held-out-probe K] [--error-blocks S] "
                 "[--cost-resolution-directions K] [--units I,J,...] [--stick-creep on|off] "
                 "[--rig-creep V] [--clock-jitter J] [--hidden effects.NAME.PARAM=VALUE]\n";
    return 2;
  }
  const int n = std::atoi(argv[1]);
  std::uint64_t seed = 12;
  int jobs = 1, min_units = -1, min_units_valve_tube = -1, min_friction_total = -1, probe_sets = 0;
  std::string keep;  // --keep DIR: the units are written there and kept
  RefineOptions refine_options = RefineOptions::ForIdentify();
  double rig_creep = 0;                  // --rig-creep
  double clock_jitter = 0;               // --clock-jitter
  std::map<std::string, double> hidden;  // --hidden
  Start start = Start::kIdentify;
  std::vector<int> indices;  // --units: the units to run (default: all N)
  if (argc % 2 != 0) {
    std::cerr << "every flag takes a value\n";
    return 2;
  }
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string flag = argv[i], value = argv[i + 1];
    if (flag == "--seed")
      seed = std::strtoull(argv[i + 1], nullptr, 10);
    else if (flag == "--jobs")
      jobs = std::atoi(argv[i + 1]);
    else if (flag == "--min-units")
      min_units = std::atoi(argv[i + 1]);
    else if (flag == "--min-units-valve-tube")
      min_units_valve_tube = std::atoi(argv[i + 1]);
    else if (flag == "--min-friction-total")
      min_friction_total = std::atoi(argv[i + 1]);
    else if (flag == "--held-out-probe")
      probe_sets = std::atoi(argv[i + 1]);
    else if (flag == "--keep")
      keep = argv[i + 1];
    else if (flag == "--hidden") {
      const std::size_t equals = value.find('=');
      const std::string path = value.substr(0, equals);
      char* end = nullptr;
      const double number =
          equals == std::string::npos ? NAN : std::strtod(value.c_str() + equals + 1, &end);
      if (FindEffectParameter(path) == nullptr || !std::isfinite(number) || *end != '\0') {
        std::cerr << "--hidden: expected effects.NAME.PARAM=VALUE of the catalog, got " << value
                  << "\n";
        return 2;
      }
      hidden[path] = number;
    } else if (flag == "--units") {
      if (value.empty()) {
        std::cerr << "--units: an empty list\n";
        return 2;
      }
      std::stringstream list(value);
      for (std::string item; std::getline(list, item, ',');) {
        char* end = nullptr;
        const long index = std::strtol(item.c_str(), &end, 10);
        if (end == item.c_str() || *end != '\0' || index < 0) {
          std::cerr << "--units: not a unit index: " << item << "\n";
          return 2;
        }
        indices.push_back(static_cast<int>(index));
      }
    } else if (flag == "--start" && (value == "identify" || value == "truth" || value == "rig"))
      start = value == "identify" ? Start::kIdentify
              : value == "truth"  ? Start::kTruth
                                  : Start::kRig;
    else if (flag == "--start-prior" && (value == "on" || value == "off"))
      refine_options.start_prior = value == "on";
    else if (flag == "--stick-creep" && (value == "on" || value == "off"))
      refine_options.fit_stick_creep = value == "on";
    else if (flag == "--error-blocks" || flag == "--cost-resolution-directions" ||
             flag == "--relative-tolerance" || flag == "--rig-creep" || flag == "--clock-jitter") {
      char* end = nullptr;
      const double number = std::strtod(value.c_str(), &end);
      if (end == value.c_str() || *end != '\0') {
        std::cerr << flag << ": not a number: " << value << "\n";
        return 2;
      }
      if (flag == "--error-blocks")
        refine_options.clustered_error_block_s = number;
      else if (flag == "--relative-tolerance")
        refine_options.simulation.relative_tolerance = number;
      else if (flag == "--rig-creep") {
        if (!(number > 0)) {
          std::cerr << "--rig-creep: a creep speed > 0 m/s, not " << value << "\n";
          return 2;
        }
        rig_creep = number;
      } else if (flag == "--clock-jitter") {
        if (!(number >= 0 && number < 0.5)) {
          std::cerr << "--clock-jitter: a share in [0, 0.5), not " << value << "\n";
          return 2;
        }
        clock_jitter = number;
      } else
        refine_options.cost_resolution_directions = static_cast<int>(number);
    } else if (flag == "--start" || flag == "--start-prior" || flag == "--stick-creep") {
      std::cerr << flag << ": unknown value " << value << "\n";
      return 2;
    } else {
      std::cerr << "unknown flag " << flag << "\n";
      return 2;
    }
  }
  if (n < 1 || jobs < 1 || probe_sets < 0) {
    std::cerr << "N and --jobs must be >= 1, --held-out-probe >= 0\n";
    return 2;
  }
  for (int index : indices) {
    if (index >= n) {
      std::cerr << "--units: unit " << index << " is not one of the " << n << "\n";
      return 2;
    }
  }
  std::sort(indices.begin(), indices.end());
  indices.erase(std::unique(indices.begin(), indices.end()), indices.end());  // each unit once
  if (indices.empty()) {
    for (int k = 0; k < n; ++k) indices.push_back(k);
  }
  std::string invalid;
  if (!refine_options.IsValid(&invalid)) {
    std::cerr << "refine options: " << invalid << "\n";
    return 2;
  }
  const std::filesystem::path scratch = keep.empty()
                                            ? std::filesystem::temp_directory_path() /
                                                  ("pneumaid-sweep-" + std::to_string(::getpid()))
                                            : std::filesystem::path(keep);
  const int count = static_cast<int>(indices.size());
  std::vector<UnitResult> results(count);
  std::atomic<int> next{0};
  std::mutex print;
  std::vector<std::thread> workers;
  for (int w = 0; w < jobs; ++w) {
    workers.emplace_back([&] {
      for (int k = next++; k < count; k = next++) {
        results[k] = RunUnit(seed, indices[k], scratch, !keep.empty(), refine_options, start,
                             probe_sets, rig_creep, clock_jitter, hidden);
        const UnitResult& r = results[k];
        std::lock_guard<std::mutex> lock(print);
        std::printf("%s: %s\n", r.id.c_str(), r.summary.c_str());
        if (!r.friction.empty()) std::printf("  %s\n", r.friction.c_str());
        if (!r.failure.empty()) {
          std::printf("  FAILED: %s\n", r.failure.c_str());
          continue;
        }
        std::string misses, identify_misses;
        for (const auto& name : kChecked) {
          if (!r.ok.at(name)) misses += " " + name;
          if (!r.identify_ok.at(name)) identify_misses += " " + name;
        }
        std::printf(
            "  %s, chi2 %.3g (truth %.3g); misses:%s (identify:%s); held-out x %.3f mm (limit "
            "%.3f)%s; "
            "within 3 SE %d/%d; identify %.2f s, refine %.1f s\n",
            r.status.c_str(), r.chi_square, r.truth_chi_square,
            misses.empty() ? " none" : misses.c_str(),
            identify_misses.empty() ? " none" : identify_misses.c_str(), r.held_out_mm,
            r.held_out_limit_mm, r.held_out_ok ? "" : " MISSED", r.refined_errors.within_3,
            r.refined_errors.checked, r.identify_s, r.refine_s);
        if (!r.refined_errors.outside_3.empty())
          std::printf("  outside 3 SE (z):%s\n", r.refined_errors.outside_3.c_str());
        if (!r.identify_errors.outside_3.empty())
          std::printf("  identify outside 3 SE (z):%s\n", r.identify_errors.outside_3.c_str());
        if (r.probe_pass >= 0) {
          std::printf("  held-out probe: %d/%d friction sets within half the tolerances pass\n",
                      r.probe_pass, probe_sets);
        }
        std::fflush(stdout);
      }
    });
  }
  for (auto& w : workers) w.join();
  if (keep.empty()) std::filesystem::remove_all(scratch);
  std::printf(
      "\nSweep of %d synthetic units (seed %llu): share within tolerance after refinement "
      "(after identify alone)\n",
      count, static_cast<unsigned long long>(seed));
  bool enough = true;
  int friction_total = 0;
  for (const auto& name : kChecked) {
    int good = 0, identify_good = 0;
    for (const auto& r : results) {
      good += r.failure.empty() && r.ok.at(name);
      identify_good += r.failure.empty() && r.identify_ok.at(name);
    }
    std::printf("  %-15s %2d/%d (%.0f %%)  (identify %d/%d)\n", name.c_str(), good, count,
                100.0 * good / count, identify_good, count);
    enough = enough && (min_units < 0 || good >= min_units);
    const bool valve_tube = name.rfind("kvp", 0) == 0 || name == "delta";
    enough = enough && (!valve_tube || min_units_valve_tube < 0 || good >= min_units_valve_tube);
    if (!valve_tube) friction_total += good;
  }
  std::printf("  friction coefficients within tolerance: %d of %d\n", friction_total, 8 * count);
  enough = enough && (min_friction_total < 0 || friction_total >= min_friction_total);
  int held = 0, explained = 0;
  ErrorCoverage refined_errors, identify_errors;
  std::vector<double> identify, refine;
  for (const auto& r : results) {
    if (!r.failure.empty()) continue;
    held += r.held_out_ok;
    refined_errors.Add(r.refined_errors);
    identify_errors.Add(r.identify_errors);
    explained += r.explained;
    identify.push_back(r.identify_s);
    refine.push_back(r.refine_s);
  }
  std::printf("  held-out x RMSE <= 2 x truth's + 0.05 mm: %d/%d\n", held, count);
  if (probe_sets > 0) {
    int pass = 0, most = 0, few = 0;
    for (const auto& r : results) {
      if (!r.failure.empty()) continue;
      pass += r.probe_pass;
      most += 10 * r.probe_pass >= 9 * probe_sets;
      few += 10 * r.probe_pass <= 2 * probe_sets;
    }
    std::printf(
        "  held-out probe (friction within half the tolerances, all else true): %d/%d sets pass; "
        "units where at least 90 %% pass: %d, at most 20 %%: %d\n",
        pass, count * probe_sets, most, few);
  }
  // Errors honest both ways: a normal error puts 68 % within one standard
  // error; far more says the errors are wider than the fits' spread.
  for (const auto& [what, e] : {std::make_pair("refined", &refined_errors),
                                std::make_pair("identified", &identify_errors)}) {
    std::printf(
        "  %s coefficients within 3 standard errors: %d/%d (%.0f %%); within 1: %d (%.0f %%)\n",
        what, e->within_3, e->checked, e->checked ? 100.0 * e->within_3 / e->checked : 0.0,
        e->within_1, e->checked ? 100.0 * e->within_1 / e->checked : 0.0);
  }
  std::printf("  refinement verdict 'explained': %d/%d\n", explained, count);
  std::vector<double> at_truth;
  for (const auto& r : results)
    if (r.failure.empty()) at_truth.push_back(r.truth_chi_square);
  std::sort(at_truth.begin(), at_truth.end());
  if (!at_truth.empty()) {
    std::printf("  median reduced chi-square at the truth: median %.3g, largest %.3g\n",
                Median(at_truth), at_truth.back());
  }
  std::printf("  median identify %.2f s, median identify --refine %.1f s (refine alone)\n",
              Median(identify), Median(refine));
  return enough ? 0 : 1;
}
