#include "pneumaid/validate/logged_run.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "../util/median.h"
#include "../util/slope.h"
#include "pneumaid/eval/metrics.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/log_notes.h"
#include "pneumaid/model/load.h"
#include "pneumaid/validate/lag_start.h"

namespace pneumaid {
namespace {

constexpr double kGeometryTolerance = 0.01;

bool Stated(const Manifest& manifest, const std::string& path) {
  for (const auto& used : manifest.defaults_used) {
    if (used == path) return false;
  }
  return true;
}

// `key`: the manifest's rig key the message points at (its line).
void CheckGeometry(const Unit& unit, const std::string& what, const std::string& key,
                   double from_manifest, double from_params, bool stated) {
  if (!stated || std::fabs(from_manifest / from_params - 1.0) <= kGeometryTolerance) return;
  char message[256];
  std::snprintf(message, sizeof(message),
                "geometry disagrees with the parameter set by more than 1 %%: %s is %.6g here, "
                "%.6g in the parameter set",
                what.c_str(), from_manifest, from_params);
  const auto line = unit.manifest.lines.find(key);
  throw InputError(unit.manifest_path(), line != unit.manifest.lines.end() ? line->second : 0, 0,
                   message);
}

// The log's conditions: supply and atmospheric pressure, gas temperature,
// orientation and load mass.
void ApplyRigConditions(const RigConstants& rig, Parameters* params) {
  params->supply.supply_pressure_Pa = rig.supply_pressure_Pa;
  params->supply.atmospheric_pressure_Pa = rig.atmospheric_pressure_Pa;
  params->gas.temperature_K = rig.gas.temperature_K;
  params->cylinder.orientation = rig.orientation;
  params->cylinder.load_mass_kg = rig.load_mass_kg;
}

}  // namespace

PositionZero ReadPositionZero(const Unit& unit) {
  const RigConstants& rig = unit.manifest.rig;
  const double half = 0.5 * rig.stroke_m;
  const double weight_N =
      rig.orientation == Orientation::kVertical ? rig.load_mass_kg * kStandardGravity_m_per_s2 : 0;
  const double pressing_N =
      0.5 * (rig.supply_pressure_Pa - rig.atmospheric_pressure_Pa) * rig.area_2_m2();
  std::vector<double> rests[2];  // median positions minus the stop's
  for (const Experiment& e : unit.experiments) {
    const auto &x = e.column("x"), &p1 = e.column("p1"), &p2 = e.column("p2");
    if (x.empty() || p1.empty() || p2.empty()) continue;
    // Which stop sample i is pressed against: 0 retracted, 1 extended, -1 none.
    const auto stop = [&](std::size_t i) {
      const double force = PneumaticAndGravityForce(p1[i], p2[i], rig.atmospheric_pressure_Pa,
                                                    rig.area_1_m2(), rig.area_2_m2(), weight_N);
      if (x[i] < -half + 1e-3 && force < -pressing_N) return 0;
      if (x[i] > half - 1e-3 && force > pressing_N) return 1;
      return -1;
    };
    for (std::size_t i = 0; i < x.size();) {
      const int end = stop(i);
      std::size_t j = i + 1;
      double low = x[i], high = x[i];
      while (end >= 0 && j < x.size() && stop(j) == end) {
        low = std::min(low, x[j]);
        high = std::max(high, x[j]);
        if (high - low > kStopRestBand_m) break;
        ++j;
      }
      if (end >= 0 && j - i >= kMinStopRestSamples) {
        rests[end].push_back(
            internal::Median(std::vector<double>(x.begin() + static_cast<long>(i),
                                                 x.begin() + static_cast<long>(j))) -
            (end == 0 ? -half : half));
      }
      i = j;
    }
  }
  PositionZero out;
  double sum = 0;
  int ends = 0;
  for (int end = 0; end < 2; ++end) {
    out.rests[end] = static_cast<int>(rests[end].size());
    if (rests[end].empty()) continue;
    out.from_stop_m[end] = internal::Median(rests[end]);
    sum += out.from_stop_m[end];
    ++ends;
  }
  if (ends == 0) return out;
  const double offset = sum / ends;
  if (std::fabs(offset) >= kMinPositionZero_m) out.offset_m = offset;
  char line[160];
  out.note = "position zero: the rod rests";
  for (int end = 0; end < 2; ++end) {
    if (out.rests[end] == 0) continue;
    std::snprintf(line, sizeof(line), "%s %+.3f mm from the %s stop (%d rests)",
                  end == 1 && out.rests[0] > 0 ? " and" : "", out.from_stop_m[end] * 1e3,
                  end == 0 ? "retracted" : "extended", out.rests[end]);
    out.note += line;
  }
  if (out.offset_m == 0) {
    out.note += ": x read as logged";
  } else {
    std::snprintf(line, sizeof(line), ": x read %.3f mm %s (a transducer's zero)",
                  std::fabs(out.offset_m) * 1e3, out.offset_m > 0 ? "lower" : "higher");
    out.note += line;
  }
  return out;
}

Trajectory LoggedTrajectory(const Experiment& e, const PositionZero& zero) {
  Trajectory out = e.AsTrajectory();
  for (double& x : out.x_m) x -= zero.offset_m;
  return out;
}

namespace {

// The rod's speed at a moving start: the least-squares slope of x over the
// first kStartVelocity_s (at least three samples). A piece after a logger's
// pause starts mid-slide, and from rest the simulated rod lagged behind.
constexpr double kStartVelocity_s = 0.005;
double StartVelocity(const Trajectory& m) {
  std::size_t n = 1;
  while (n < m.size() && (n < 3 || m.t_s[n] - m.t_s.front() <= kStartVelocity_s)) ++n;
  return n < 3 ? 0.0 : internal::LeadingSlope(m.t_s, m.x_m, n);
}

// A pressure over samples [first, n) read at t[0] off the least-squares
// polynomial of the lowest degree (0 to 2) whose next term is not
// significant: a term is taken when its coefficient is over
// kStartDriftSigmas standard errors and the samples are at least its degree
// plus 2 (three samples of a chamber filling 2 kPa a sample before it
// leaves the band: their line).
struct LeadingFit {
  int degree = 0;
  double at_start = 0;  // the polynomial's value at the log's first sample
  double samples = 1;   // the mean's count whose variance the value has: 1 / (A'A)^-1 [0, 0]
};
LeadingFit FitLeading(const std::vector<double>& t, const std::vector<double>& v, std::size_t first,
                      std::size_t n) {
  const int count = static_cast<int>(n - first);
  LeadingFit fit;
  fit.at_start = v[first];  // one sample: itself
  const double span = t[n - 1] - t[0];
  for (int degree = 0; degree <= 2 && count >= degree + 2; ++degree) {
    Eigen::MatrixXd a(count, degree + 1);
    Eigen::VectorXd b(count);
    for (int i = 0; i < count; ++i) {
      const double s = span > 0 ? (t[first + i] - t[0]) / span : 0.0;
      for (int k = 0; k <= degree; ++k) a(i, k) = std::pow(s, k);
      b(i) = v[first + i];
    }
    const Eigen::MatrixXd normal = a.transpose() * a;
    const Eigen::LDLT<Eigen::MatrixXd> solve(normal);
    const Eigen::VectorXd c = solve.solve(a.transpose() * b);
    // A residual under 1 Pa is a logger's rounding, not a measure of noise.
    const double variance = std::max(1.0, (b - a * c).squaredNorm() / (count - degree - 1));
    const Eigen::MatrixXd inverse = solve.solve(Eigen::MatrixXd::Identity(degree + 1, degree + 1));
    const double se = std::sqrt(variance * inverse(degree, degree));
    if (degree > 0 && !(se > 0 && std::fabs(c(degree)) > kStartDriftSigmas * se)) break;
    fit.degree = degree;
    fit.at_start = c(0);
    fit.samples = 1.0 / inverse(0, 0);
  }
  return fit;
}

}  // namespace

// The state a run starts from: the mean of its leading samples while the
// command and the pressures stay put (at most 50), so that one noisy first
// sample does not set the start. A log that starts moving gets its first
// sample and the speed its first samples show.
InitialState LoggedInitialState(const Trajectory& m, double half_stroke_m, int* samples_averaged) {
  // A first sample a spike threw off (a pressure further than the band from
  // the second sample and from the line through the second and third, which
  // a chamber filling from the first sample follows) is left out: the band
  // is measured from the second.
  const auto spike = [&m](const std::vector<double>& p) {
    return m.size() >= 3 && std::fabs(p[0] - p[1]) > kStartPressureBand_Pa &&
           std::fabs(p[0] - (2 * p[1] - p[2])) > kStartPressureBand_Pa;
  };
  const std::size_t first = spike(m.p1_Pa) || spike(m.p2_Pa) ? 1 : 0;
  std::size_t n = first + 1;
  // A logger's noise on the command is not a change (as HeldLevels reads it).
  const auto still = [&m, first](std::size_t i) {
    return std::fabs(m.u_V[i] - m.u_V[first]) <= kCommandNoise_V &&
           std::fabs(m.p1_Pa[i] - m.p1_Pa[first]) <= kStartPressureBand_Pa &&
           std::fabs(m.p2_Pa[i] - m.p2_Pa[first]) <= kStartPressureBand_Pa;
  };
  while (n < m.size() && n < first + 50 && still(n)) ++n;
  const auto mean = [first, n](const std::vector<double>& v) {
    return std::accumulate(v.begin() + static_cast<long>(first), v.begin() + static_cast<long>(n),
                           0.0) /
           static_cast<double>(n - first);
  };
  InitialState initial;
  initial.position_m = mean(m.x_m);
  initial.p1_Pa = mean(m.p1_Pa);
  initial.p2_Pa = mean(m.p2_Pa);
  double averaged = static_cast<double>(n - first);
  // Where the start is unsettled (lag_start.h), pressures that drift over
  // those samples (a chamber still filling or emptying) are read at the
  // first sample off their fits (FitLeading): the mean lags by half the span
  // (2 kPa, seven noise sigmas, on a chamber emptying 1 kPa/ms). Not on a
  // settled start: a slow drift the fit took for significant moved the
  // refinement's start priors (N = 40: 294 -> 282 within tolerance).
  const bool unsettled = StartsUnsettled(m);
  if (unsettled) {
    const LeadingFit fit1 = FitLeading(m.t_s, m.p1_Pa, first, n);
    const LeadingFit fit2 = FitLeading(m.t_s, m.p2_Pa, first, n);
    if (fit1.degree > 0 || fit2.degree > 0) {
      initial.p1_Pa = fit1.at_start;
      initial.p2_Pa = fit2.at_start;
      averaged = std::min(fit1.samples, fit2.samples);
    }
  }
  const double moved = std::fabs(m.x_m[n - 1] - m.x_m[first]);
  if (moved > kMovedAtStart_m) {  // not at rest: averaging would blur a moving start
    initial.position_m = m.x_m[first];
    initial.velocity_m_per_s = StartVelocity(m);
    initial.p1_Pa = m.p1_Pa[first];
    initial.p2_Pa = m.p2_Pa[first];
    averaged = 1.0;
    if (unsettled) {  // the pressures off their fits over the samples the speed is read from
      std::size_t span = first + 1;
      while (span < m.size() &&
             (span < first + 3 || m.t_s[span] - m.t_s[first] <= kStartVelocity_s))
        ++span;
      const LeadingFit moving1 = FitLeading(m.t_s, m.p1_Pa, first, span);
      const LeadingFit moving2 = FitLeading(m.t_s, m.p2_Pa, first, span);
      initial.p1_Pa = moving1.at_start;
      initial.p2_Pa = moving2.at_start;
      averaged = std::min(moving1.samples, moving2.samples);
    }
  }
  if (samples_averaged != nullptr)
    *samples_averaged = std::max(1, static_cast<int>(std::lround(averaged)));
  // A rod resting on an end stop reads up to a few noise sigmas beyond it.
  initial.position_m = std::clamp(initial.position_m, -half_stroke_m, half_stroke_m);
  return initial;
}

namespace {

// `command` (a logged one, its first value holding before its first knot)
// with the lags settled for `before_V` before t0_s and its logged value from
// t0_s on (a knot added there when it has none).
CommandSignal SettledBefore(CommandSignal command, double t0_s, double before_V) {
  if (command.time_s.empty() || command.time_s.front() > t0_s) {
    const double u0 = command.ValueAt(t0_s);
    command.time_s.insert(command.time_s.begin(), t0_s);
    command.value_V.insert(command.value_V.begin(), u0);
  }
  command.initial_V = before_V;
  return command;
}

}  // namespace

CommandSignal LoggedCommand(const Trajectory& m, const RigConstants& rig,
                            std::optional<double> logged_before_V) {
  CommandSignal command = SampledCommand(m.t_s, m.u_V);
  if (m.size() < 2 || m.x_m.size() != m.size() || m.p1_Pa.size() != m.size() ||
      m.p2_Pa.size() != m.size()) {
    return command;
  }
  const double u0 = m.u_V.front();
  if (std::fabs(u0) <= kCommandNoise_V) return command;
  if (logged_before_V && std::fabs(*logged_before_V - u0) <= kCommandNoise_V) return command;
  std::size_t k = 0;
  while (k + 1 < m.size() && m.t_s[k + 1] - m.t_s.front() <= kStepRest_s) ++k;
  if (std::fabs(m.x_m[k] - m.x_m.front()) > kMovedAtStart_m) return command;
  const double at_supply_Pa =
      rig.atmospheric_pressure_Pa + 0.9 * (rig.supply_pressure_Pa - rig.atmospheric_pressure_Pa);
  const double charged_Pa = u0 > 0 ? m.p1_Pa.front() : m.p2_Pa.front();
  if (charged_Pa >= at_supply_Pa) return command;  // settled for u0
  const double discharged_Pa = u0 > 0 ? m.p2_Pa.front() : m.p1_Pa.front();
  return SettledBefore(std::move(command), m.t_s.front(),
                       discharged_Pa >= at_supply_Pa ? -u0 : 0.0);
}

std::vector<std::size_t> PieceStarts(const Trajectory& m) {
  std::vector<std::size_t> starts = {0};
  const std::vector<double>& t = m.t_s;
  const auto held = [&m](std::size_t a, std::size_t b) {  // the same command at samples a, b
    return std::fabs(m.u_V[a] - m.u_V[b]) <= kCommandNoise_V;
  };
  for (std::size_t i : SamplingGaps(t)) {
    // A held command that stepped inside the gap: held on both sides, not across.
    const bool stepped =
        i > 0 && i + 2 < t.size() && held(i - 1, i) && held(i + 1, i + 2) && !held(i, i + 1);
    if (stepped || t[i + 1] - t[i] >= kLoggerPause_s) starts.push_back(i + 1);
  }
  return starts;
}

Trajectory Slice(const Trajectory& run, std::size_t begin, std::size_t end) {
  Trajectory out;
  const auto cut = [&](const std::vector<double>& from, std::vector<double>* to) {
    if (!from.empty()) to->assign(from.begin() + begin, from.begin() + end);
  };
  cut(run.t_s, &out.t_s);
  cut(run.u_V, &out.u_V);
  cut(run.x_m, &out.x_m);
  cut(run.v_m_per_s, &out.v_m_per_s);
  cut(run.p1_Pa, &out.p1_Pa);
  cut(run.p2_Pa, &out.p2_Pa);
  cut(run.q1_kg_per_s, &out.q1_kg_per_s);
  cut(run.q2_kg_per_s, &out.q2_kg_per_s);
  return out;
}

std::optional<Unit> OnTheSetsStroke(const Unit& unit, const Parameters& params) {
  const double manifest_m = unit.manifest.rig.stroke_m;
  const double set_m = params.cylinder.stroke_m;
  if (unit.manifest.rig.position_origin != PositionOrigin::kRetracted || manifest_m == set_m) {
    return std::nullopt;
  }
  Unit moved = unit;
  moved.manifest.rig.stroke_m = set_m;
  const double shift_m = 0.5 * (manifest_m - set_m);  // logged - L/2, with the set's L
  for (Experiment& e : moved.experiments) {
    const auto x = e.columns.find("x");
    if (x == e.columns.end()) continue;
    for (double& value : x->second) value += shift_m;
  }
  return moved;
}

Parameters WithRigConditions(const Parameters& params, const Unit& unit) {
  const Manifest& m = unit.manifest;
  const RigConstants& rig = m.rig;
  const bool rod_stated = Stated(m, "rig.cylinder.rod");
  CheckGeometry(unit, "area_1 from rig.cylinder.bore", "rig.cylinder.bore", rig.area_1_m2(),
                params.cylinder.area_1_m2, Stated(m, "rig.cylinder.bore"));
  CheckGeometry(unit, "area_2 from rig.cylinder.bore and rod",
                rod_stated ? "rig.cylinder.rod" : "rig.cylinder.bore", rig.area_2_m2(),
                params.cylinder.area_2_m2, Stated(m, "rig.cylinder.bore") || rod_stated);
  for (const auto& [key, from_manifest, from_params] :
       {std::make_tuple("rig.cylinder.stroke", rig.stroke_m, params.cylinder.stroke_m),
        std::make_tuple("rig.cylinder.dead_volume_1", rig.dead_volume_1_m3,
                        params.cylinder.dead_volume_1_m3),
        std::make_tuple("rig.cylinder.dead_volume_2", rig.dead_volume_2_m3,
                        params.cylinder.dead_volume_2_m3)}) {
    CheckGeometry(unit, key, key, from_manifest, from_params, Stated(m, key));
  }
  Parameters out = params;
  ApplyRigConditions(rig, &out);
  return out;
}

Parameters WithUnitConstants(const Parameters& params, const Unit& unit) {
  const RigConstants& rig = unit.manifest.rig;
  Parameters out = params;
  out.unit = unit.manifest.unit;
  ApplyRigConditions(rig, &out);
  out.gas = rig.gas;  // the unit's gas whole, not only its temperature
  out.cylinder.area_1_m2 = rig.area_1_m2();
  out.cylinder.area_2_m2 = rig.area_2_m2();
  out.cylinder.stroke_m = rig.stroke_m;
  out.cylinder.dead_volume_1_m3 = rig.dead_volume_1_m3;
  out.cylinder.dead_volume_2_m3 = rig.dead_volume_2_m3;
  out.pipeline.tube_length_m = rig.tube_length_m;
  return out;
}

// The simulated run as the rig's instruments would have logged it: every
// channel through its declared instrument lag (flow meters, and any lag
// declared for the position or pressure transducers).
void ApplyDeclaredLags(const Manifest& manifest, Trajectory* run) {
  for (const auto& [name, values] :
       {std::make_pair("x", &run->x_m), std::make_pair("p1", &run->p1_Pa),
        std::make_pair("p2", &run->p2_Pa), std::make_pair("q1", &run->q1_kg_per_s),
        std::make_pair("q2", &run->q2_kg_per_s)}) {
    const double tau_s = manifest.DeclaredTau(name, 0.0);
    if (tau_s > 0) *values = FirstOrderLag(run->t_s, *values, tau_s);
  }
}

}  // namespace pneumaid
