// Refinement (refine.h), its runs: which logged experiments are fitted, each
// as the fit sees it (measured trajectory, command, logged start, weighted
// channels, estimated start pressures), and the windows of multiple shooting.
#pragma once

#include <array>
#include <map>
#include <string>
#include <vector>

#include "pneumaid/ident/fit_spec.h"
#include "pneumaid/ident/refine.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/sim/command.h"
#include "pneumaid/sim/sensitivities.h"
#include "pneumaid/sim/simulate.h"
#include "pneumaid/validate/logged_run.h"

namespace pneumaid::refine_internal {

struct Channel {
  std::string name;
  std::vector<double> Trajectory::*values;
  Eigen::MatrixXd TrajectorySensitivities::*derivatives;
  double factor;       // weight / sigma
  double meter_tau_s;  // the channel's declared instrument lag, 0 when none
};

// Nuisance coordinates of an estimated start: the offsets of p1(t0), p2(t0)
// from their logged values in units of their standard errors (0: as logged).
constexpr int kStartOffsets = kInitialPressureColumns;
using StartOffsets = std::array<double, kStartOffsets>;

struct FitExperiment {
  std::string id;
  Trajectory measured;
  CommandSignal command;
  InitialState initial;
  std::vector<Channel> channels;
  // The run a window (multiple shooting) or a piece (a logger's pause:
  // Pieces) is part of; empty for a whole run.
  std::string parent;
  // Standard errors of the logged initial p1, p2 [Pa] when they are estimated
  // (FitSpec::fit_initial_pressures); {0, 0}: the start is taken as logged.
  std::array<double, kStartOffsets> start_sigma_Pa = {0, 0};

  bool FitsStart() const { return start_sigma_Pa[0] > 0; }
  // The data's rows: one per sample and channel.
  long data_rows() const { return static_cast<long>(measured.size() * channels.size()); }
  // Data rows, then one prior row per estimated initial pressure.
  long residuals() const { return data_rows() + (FitsStart() ? kStartOffsets : 0); }
};

// The coordinates z of an experiment's residual block: the free parameters'
// theta, then its start offsets when it FitsStart (`offsets` unused otherwise).
inline std::vector<double> Coordinates(const FitExperiment& e, const double* theta, int m,
                                       const double* offsets) {
  std::vector<double> z(theta, theta + m);
  if (e.FitsStart()) z.insert(z.end(), offsets, offsets + kStartOffsets);
  return z;
}

// The run's start with the offsets applied.
InitialState StartOf(const FitExperiment& e, const double* offsets);

// The rows of the residual table: x, p1, p2, q1, q2.
extern const Channel kChannelTable[5];

// The spec's two lists of experiments.
enum class ExperimentList { kFit, kHoldOut };

// The experiments one of the spec's lists names by id or kind; InputError
// (the spec's file and the entry's line) for a name that matches none (a
// kind the unit lacks only when must_match) or a run that cannot be refined on.
std::vector<const Experiment*> Select(const Unit& unit, const FitSpec& spec, ExperimentList list,
                                      bool must_match);

// The noise sigma [SI] of each channel of the residual table that the spec
// fits: the spec's when it gives one, else the unit's (NoiseOf: declared under
// the manifest's `sensors`, or estimated from its logs; 0 when neither can be
// had).
std::map<std::string, double> ChannelSigmas(const FitSpec& spec, const Unit& unit);

// The noise sigmas of one logged sample of p1 and p2 (`sigmas` where the spec
// fits them, else the unit's NoiseSigma), when the spec estimates starts and
// both are known; {0, 0} (the start is taken as logged) otherwise.
std::array<double, kStartOffsets> StartSampleSigma(const FitSpec& spec, const Unit& unit,
                                                   const std::map<std::string, double>& sigmas);

// One logged run as the fit sees it. `sigmas`: ChannelSigmas(spec, unit);
// `sample_sigma_Pa`: StartSampleSigma(spec, unit, sigmas); `zero`:
// ReadPositionZero(unit).
FitExperiment Prepare(const Experiment& e, const Unit& unit, const FitSpec& spec,
                      double half_stroke_m, const std::map<std::string, double>& sigmas,
                      const std::array<double, kStartOffsets>& sample_sigma_Pa,
                      const PositionZero& zero);

// A run cut where its logger paused (PieceStarts, logged_run.h): each piece
// from its own logged start (LoggedInitialState) with the command as its own
// log gives it (LoggedCommand), named `id@t` with the run as its parent, so
// that the verdict, the clustered errors and the windows count it with its
// run. A run without a pause is its only piece.
std::vector<FitExperiment> Pieces(const FitExperiment& run, const RigConstants& rig,
                                  double half_stroke_m,
                                  const std::array<double, kStartOffsets>& sample_sigma_Pa);

// Multiple shooting (FitStage::windows): the run cut where the rod has come
// to rest in a stuck phase (ArrivalSample; stuck as the friction fit reads it
// with FrictionFitOptions' defaults, for position noise `sigma_x_m`), each
// window simulated from its logged state (the phase's rest position, v = 0),
// with the command-driven lags replayed from the start of the log (of the
// piece). A window's parent is its run (a piece's, the piece's run).
std::vector<FitExperiment> Windows(const FitExperiment& run, double sigma_x_m, double half_stroke_m,
                                   const std::array<double, kStartOffsets>& sample_sigma_Pa);

// The experiments `spec` fits on `unit` (CheckRefinable's rules).
std::vector<const Experiment*> RunsToFit(const FitSpec& spec, const Unit& unit);

// The fitted runs of a spec, whole or cut into windows; InputError when none,
// or when a run is both fitted and held out. A run (a piece) in
// `lag_starts` (RefineOptions::lag_starts, by id) starts with its read lag
// start; every other run (all, for null) as logged.
std::vector<FitExperiment> FittedRuns(const Parameters& conditioned, const Unit& unit,
                                      const FitSpec& spec, bool windows,
                                      const std::map<std::string, LagStart>* lag_starts);

// The lag starts of the spec's fitted runs read at `conditioned` under
// `simulation` (ReadLagStart, lag_start.h), by run (piece) id: those read
// only.
std::map<std::string, LagStart> ReadLagStarts(const Parameters& conditioned, const Unit& unit,
                                              const FitSpec& spec,
                                              const SimulationOptions& simulation);

// Windows' costs summed per run, in the order the runs first appear.
std::vector<ExperimentCost> PerRun(const std::vector<ExperimentCost>& costs,
                                   const std::vector<FitExperiment>& runs);

}  // namespace pneumaid::refine_internal
