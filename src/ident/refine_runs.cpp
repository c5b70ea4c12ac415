#include "refine_runs.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "pneumaid/io/channel_noise.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/validate/lag_start.h"
#include "pneumaid/validate/validate.h"
#include "stuck_phases.h"

namespace pneumaid::refine_internal {

// The run's start with the offsets applied.
InitialState StartOf(const FitExperiment& e, const double* offsets) {
  InitialState initial = e.initial;
  if (e.FitsStart()) {
    initial.p1_Pa += offsets[0] * e.start_sigma_Pa[0];
    initial.p2_Pa += offsets[1] * e.start_sigma_Pa[1];
  }
  return initial;
}

const Channel kChannelTable[5] = {
    {"x", &Trajectory::x_m, &TrajectorySensitivities::x, 0, 0},
    {"p1", &Trajectory::p1_Pa, &TrajectorySensitivities::p1, 0, 0},
    {"p2", &Trajectory::p2_Pa, &TrajectorySensitivities::p2, 0, 0},
    {"q1", &Trajectory::q1_kg_per_s, &TrajectorySensitivities::q1, 0, 0},
    {"q2", &Trajectory::q2_kg_per_s, &TrajectorySensitivities::q2, 0, 0}};

namespace {

// The spec file's line of an entry (0: a spec built in code).
int LineOf(const std::map<std::string, int>& lines, const std::string& name) {
  const auto it = lines.find(name);
  return it == lines.end() ? 0 : it->second;
}

}  // namespace

std::vector<const Experiment*> Select(const Unit& unit, const FitSpec& spec, ExperimentList list,
                                      bool must_match) {
  const bool fit = list == ExperimentList::kFit;
  const std::vector<std::string>& names = fit ? spec.fit : spec.hold_out;
  const std::map<std::string, int>& lines = fit ? spec.fit_lines : spec.hold_out_lines;
  std::vector<const Experiment*> chosen;
  for (const std::string& name : names) {
    bool matched = false;
    for (const Experiment& e : unit.experiments) {
      const bool by_kind = name == ToString(e.entry.kind);
      if (!by_kind && e.entry.id != name) continue;
      matched = true;
      if (!IsSimulable(e.entry.kind)) {
        if (by_kind) continue;
        throw InputError(spec.Name(), LineOf(lines, name), 0,
                         "experiment '" + name + "' is a " + ToString(e.entry.kind) +
                             " log; only stroke and validation runs can be refined on");
      }
      if (std::find(chosen.begin(), chosen.end(), &e) == chosen.end()) chosen.push_back(&e);
    }
    const bool is_kind = name == "stroke" || name == "validation";
    if (!matched && (must_match || !is_kind)) {
      if (is_kind) {  // the unit lacks what a spec may rightly ask of any unit
        throw InputError(
            unit.manifest_path(), 0, 0,
            "the unit has no " + name + " experiment, and " +
                (spec.source.empty() ? "the fit spec" : "the fit spec " + spec.source) + " fits '" +
                name + "': the refinement has no run to fit");
      }
      throw InputError(spec.Name(), LineOf(lines, name), 0,
                       (fit ? "experiments.fit: " : "experiments.hold_out: ") +
                           std::string("no experiment '") + name + "' (an id or a kind) in " +
                           unit.manifest_path());
    }
  }
  return chosen;
}

std::map<std::string, double> ChannelSigmas(const FitSpec& spec, const Unit& unit) {
  std::map<std::string, double> sigmas;
  for (const Channel& row : kChannelTable) {
    const auto given = spec.channels.find(row.name);
    if (given == spec.channels.end()) continue;
    sigmas[row.name] = given->second.sigma > 0 ? given->second.sigma : NoiseSigma(unit, row.name);
  }
  return sigmas;
}

std::array<double, kStartOffsets> StartSampleSigma(const FitSpec& spec, const Unit& unit,
                                                   const std::map<std::string, double>& sigmas) {
  const auto sigma = [&](const char* channel) {  // a pressure the spec does not fit: the unit's
    const auto found = sigmas.find(channel);
    return found == sigmas.end() ? NoiseSigma(unit, channel) : found->second;
  };
  const double p1 = sigma("p1"), p2 = sigma("p2");
  if (!spec.fit_initial_pressures || !(p1 > 0 && p2 > 0)) return {0, 0};
  return {p1, p2};
}

// A run's command and start as its log gives them (logged_run.h), and the
// standard errors of its start's pressures: a sample's, over the samples the
// start is the mean of. `logged_before_V`: LoggedCommand's.
void StartFromLog(const RigConstants& rig, double half_stroke_m,
                  const std::array<double, kStartOffsets>& sample_sigma_Pa,
                  std::optional<double> logged_before_V, FitExperiment* run) {
  run->command = LoggedCommand(run->measured, rig, logged_before_V);
  int averaged = 1;
  run->initial = LoggedInitialState(run->measured, half_stroke_m, &averaged);
  const double root_n = std::sqrt(static_cast<double>(averaged));
  for (int k = 0; k < kStartOffsets; ++k) run->start_sigma_Pa[k] = sample_sigma_Pa[k] / root_n;
}

FitExperiment Prepare(const Experiment& e, const Unit& unit, const FitSpec& spec,
                      double half_stroke_m, const std::map<std::string, double>& sigmas,
                      const std::array<double, kStartOffsets>& sample_sigma_Pa,
                      const PositionZero& zero) {
  FitExperiment out;
  out.id = e.entry.id;
  out.measured = LoggedTrajectory(e, zero);
  StartFromLog(unit.manifest.rig, half_stroke_m, sample_sigma_Pa, std::nullopt, &out);
  for (const Channel& row : kChannelTable) {
    const auto wanted = spec.channels.find(row.name);
    if (wanted == spec.channels.end() || (out.measured.*row.values).empty()) continue;
    const double sigma = sigmas.at(row.name);
    if (!(sigma > 0)) {
      throw InputError(spec.Name(), 0, 0,
                       "channel " + row.name + ": no sigma given, none declared under sensors in " +
                           unit.manifest_path() + ", and its logs never change");
    }
    Channel c = row;
    c.factor = wanted->second.weight / sigma;
    c.meter_tau_s = unit.manifest.DeclaredTau(row.name, 0.0);
    out.channels.push_back(c);
  }
  if (out.channels.empty()) {
    throw InputError(spec.Name(), 0, 0, "experiment '" + out.id + "' logs none of the channels");
  }
  return out;
}

// A window is at least this long.
constexpr std::size_t kMinWindowSamples = 20;

// Pieces (refine_runs.h). A piece of one sample has nothing to simulate.
std::vector<FitExperiment> Pieces(const FitExperiment& run, const RigConstants& rig,
                                  double half_stroke_m,
                                  const std::array<double, kStartOffsets>& sample_sigma_Pa) {
  const std::vector<std::size_t> begins = PieceStarts(run.measured);
  if (begins.size() <= 1) return {run};
  std::vector<FitExperiment> pieces;
  for (std::size_t k = 0; k < begins.size(); ++k) {
    const std::size_t begin = begins[k];
    const std::size_t end = k + 1 < begins.size() ? begins[k + 1] : run.measured.size();
    if (end - begin < 2) continue;
    FitExperiment piece = run;
    piece.measured = Slice(run.measured, begin, end);
    piece.id = run.id + "@" + FormatDouble(run.measured.t_s[begin]);
    piece.parent = run.id;
    StartFromLog(rig, half_stroke_m, sample_sigma_Pa,
                 begin > 0 ? std::optional<double>(run.measured.u_V[begin - 1]) : std::nullopt,
                 &piece);
    pieces.push_back(std::move(piece));
  }
  return pieces;
}

// Multiple shooting's windows (refine_runs.h).
std::vector<FitExperiment> Windows(const FitExperiment& run, double sigma_x_m, double half_stroke_m,
                                   const std::array<double, kStartOffsets>& sample_sigma_Pa) {
  const std::vector<double>& x = run.measured.x_m;
  const std::vector<double>& t = run.measured.t_s;
  const std::size_t n = x.size();
  std::vector<std::size_t> starts = {0};
  std::vector<double> rest_positions = {run.initial.position_m};
  if (n >= 2 * kMinWindowSamples) {
    const double period_s = (t.back() - t.front()) / static_cast<double>(n - 1);
    const internal::StuckRule rule = internal::StuckRuleOf(FrictionFitOptions{}, sigma_x_m,
                                                           internal::PositionQuantum(x), period_s);
    for (const auto& phase : internal::StuckRuns(x, rule)) {
      const std::size_t begin = internal::ArrivalSample(x, phase, rule);
      if (begin - starts.back() < kMinWindowSamples || n - begin < kMinWindowSamples) continue;
      starts.push_back(begin);
      rest_positions.push_back(internal::RestPosition(x, phase));
    }
  }
  std::vector<FitExperiment> windows;
  for (std::size_t w = 0; w < starts.size(); ++w) {
    const std::size_t begin = starts[w], end = w + 1 < starts.size() ? starts[w + 1] : n;
    FitExperiment window = run;
    window.measured = Slice(run.measured, begin, end);
    window.id = run.id + "@" + FormatDouble(run.measured.t_s[begin]);
    window.parent = run.parent.empty() ? run.id : run.parent;
    if (begin > 0) {
      window.initial = InitialState{};
      window.initial.position_m = std::clamp(rest_positions[w], -half_stroke_m, half_stroke_m);
      window.initial.p1_Pa = run.measured.p1_Pa[begin];
      window.initial.p2_Pa = run.measured.p2_Pa[begin];
      window.initial.lag_history_from_s = std::isnan(run.initial.lag_history_from_s)
                                              ? run.measured.t_s.front()
                                              : run.initial.lag_history_from_s;
      if (run.FitsStart()) window.start_sigma_Pa = sample_sigma_Pa;  // one sample each
    }
    windows.push_back(std::move(window));
  }
  return windows;
}

std::vector<const Experiment*> RunsToFit(const FitSpec& spec, const Unit& unit) {
  const auto fitted = Select(unit, spec, ExperimentList::kFit, true);
  for (const Experiment* e : Select(unit, spec, ExperimentList::kHoldOut, false)) {
    if (std::count(fitted.begin(), fitted.end(), e)) {
      // The hold-out entry that names it (by id, else by kind).
      const std::string& kind = ToString(e->entry.kind);
      const int line =
          LineOf(spec.hold_out_lines, spec.hold_out_lines.count(e->entry.id) ? e->entry.id : kind);
      throw InputError(spec.Name(), line, 0,
                       "experiment '" + e->entry.id + "' is both fitted and held out");
    }
  }
  if (fitted.empty()) throw InputError(spec.Name(), 0, 0, "no experiment to fit");
  return fitted;
}

namespace {

// The noise a lag start is read by: the spec's sigma of x, p1 and p2, else the unit's.
std::map<std::string, double> LagStartNoise(const std::map<std::string, double>& sigmas,
                                            const Unit& unit) {
  std::map<std::string, double> noise;
  for (const char* channel : {"x", "p1", "p2"}) {
    const auto given = sigmas.find(channel);
    noise[channel] = given != sigmas.end() ? given->second : NoiseSigma(unit, channel);
  }
  return noise;
}

// The spec's fitted runs cut at the loggers' pauses, as logged, with the
// spec's channel sigmas and start sigmas; each lag start read at
// `conditioned` put in `read`, when given.
std::vector<FitExperiment> FittedPieces(const Parameters& conditioned, const Unit& unit,
                                        const FitSpec& spec,
                                        const std::map<std::string, double>& sigmas,
                                        const std::array<double, kStartOffsets>& sample_sigma,
                                        const SimulationOptions& simulation,
                                        std::map<std::string, LagStart>* read) {
  const double half_stroke = 0.5 * conditioned.cylinder.stroke_m;
  const PositionZero zero = ReadPositionZero(unit);
  const std::map<std::string, double> noise =
      read != nullptr ? LagStartNoise(sigmas, unit) : std::map<std::string, double>{};
  std::vector<FitExperiment> pieces;
  for (const Experiment* e : RunsToFit(spec, unit)) {
    const FitExperiment run = Prepare(*e, unit, spec, half_stroke, sigmas, sample_sigma, zero);
    for (FitExperiment& piece : Pieces(run, unit.manifest.rig, half_stroke, sample_sigma)) {
      if (read != nullptr) {
        LagStart lag = ReadLagStart(conditioned, piece.measured, piece.command, piece.initial,
                                    noise, simulation);
        if (lag.read) (*read)[piece.id] = std::move(lag);
      }
      pieces.push_back(std::move(piece));
    }
  }
  return pieces;
}

}  // namespace

std::map<std::string, LagStart> ReadLagStarts(const Parameters& conditioned, const Unit& unit,
                                              const FitSpec& spec,
                                              const SimulationOptions& simulation) {
  std::map<std::string, LagStart> read;
  const std::map<std::string, double> sigmas = ChannelSigmas(spec, unit);
  FittedPieces(conditioned, unit, spec, sigmas, StartSampleSigma(spec, unit, sigmas), simulation,
               &read);
  return read;
}

// The fitted runs of a spec, whole or cut into windows.
std::vector<FitExperiment> FittedRuns(const Parameters& conditioned, const Unit& unit,
                                      const FitSpec& spec, bool windows,
                                      const std::map<std::string, LagStart>* lag_starts) {
  const std::map<std::string, double> sigmas = ChannelSigmas(spec, unit);
  const std::array<double, kStartOffsets> sample_sigma = StartSampleSigma(spec, unit, sigmas);
  std::vector<FitExperiment> pieces =
      FittedPieces(conditioned, unit, spec, sigmas, sample_sigma, SimulationOptions{}, nullptr);
  for (FitExperiment& piece : pieces) {
    if (lag_starts == nullptr) break;
    const auto found = lag_starts->find(piece.id);
    if (found == lag_starts->end()) continue;
    piece.command = found->second.command;
    piece.initial.lag_history_from_s = found->second.initial.lag_history_from_s;
    piece.initial.velocity_m_per_s = found->second.initial.velocity_m_per_s;
  }
  if (!windows) return pieces;
  const double half_stroke = 0.5 * conditioned.cylinder.stroke_m;
  const double sigma_x_m = internal::PositionNoise(unit);
  std::vector<FitExperiment> runs;
  for (FitExperiment& piece : pieces) {
    for (FitExperiment& window : Windows(piece, sigma_x_m, half_stroke, sample_sigma))
      runs.push_back(std::move(window));
  }
  return runs;
}

// Windows' costs summed per run, in the order the runs first appear.
std::vector<ExperimentCost> PerRun(const std::vector<ExperimentCost>& costs,
                                   const std::vector<FitExperiment>& runs) {
  std::vector<ExperimentCost> merged;
  for (size_t k = 0; k < costs.size(); ++k) {
    const std::string& id = runs[k].parent.empty() ? runs[k].id : runs[k].parent;
    if (merged.empty() || merged.back().id != id) merged.push_back({id, 0, 0, 0});
    merged.back().before += costs[k].before;
    merged.back().after += costs[k].after;
    merged.back().residuals += costs[k].residuals;
  }
  return merged;
}

}  // namespace pneumaid::refine_internal
