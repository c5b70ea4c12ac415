// How a logged run is set up for simulation: the one home of "which
// constants win", the state a run starts from and what its meters add.
// Validate, identify and refine all ask here; none applies conditions on its
// own.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "pneumaid/io/rig_data.h"
#include "pneumaid/model/parameters.h"
#include "pneumaid/sim/command.h"
#include "pneumaid/sim/simulate.h"
#include "pneumaid/trajectory.h"

namespace pneumaid {

// The parameter set under a log's conditions ("which constants win"): supply
// and atmospheric pressure, gas temperature, orientation and load mass from the
// manifest; geometry from the parameter set. Geometry the manifest states
// (bore, rod, stroke, dead volumes) that disagrees by more than 1 % is an
// InputError naming the manifest.
Parameters WithRigConditions(const Parameters& params, const Unit& unit);

// The unit's logs on the set's stroke, when they differ: a log written from
// the retracted stop is placed from mid-stroke with the manifest's stroke, so
// a set whose stroke differs (within the 1 % WithRigConditions allows) would
// put the retracted stop half the difference off its own (0.45 mm in 50:
// x RMSE 0.23 mm for 0.015). Returns a copy with x moved by that half
// difference and the manifest's stroke the set's; nullopt when the strokes
// agree or the logs are written from mid-stroke (their origin is the middle
// whatever the stroke).
std::optional<Unit> OnTheSetsStroke(const Unit& unit, const Parameters& params);

// The unit's own constants over `params` (what identify starts from): the
// conditions above, and the unit's id, gas, geometry and tube length as its
// manifest states them.
Parameters WithUnitConstants(const Parameters& params, const Unit& unit);

// The state a logged run starts from: the mean of its leading samples while
// the command has not yet changed by more than 0.01 V and the pressures stay
// within kStartPressureBand_Pa of the first sample's (at most 50: a log that
// starts at a step has its chambers filling from the first sample); its first
// sample when the rod already moves. Where the run starts unsettled
// (StartsUnsettled, lag_start.h: a log cut mid-run), pressures that drift
// over those samples (a chamber still filling or emptying) are read at the
// first sample off their least-squares polynomials instead (FitLeading), and
// a moving start's off their fits over the 5 ms its speed is read from. A first sample whose
// pressure a spike threw further than the band from the second and from the line through the second
// and third (a filling chamber's) is left out. The position is clamped to the stroke
// (+-half_stroke_m): a rod resting on an end stop reads up to a few noise
// sigmas beyond it. `samples_averaged`, if given, receives how many samples'
// mean the start's pressures are as certain as (1 for a moving start; for a
// line, 1 / (1/n + d^2/Stt), about n/4).
constexpr double kStartPressureBand_Pa = 5e3;
constexpr double kStartDriftSigmas = 3.0;
InitialState LoggedInitialState(const Trajectory& measured, double half_stroke_m,
                                int* samples_averaged = nullptr);

// The command of a logged run as the simulator takes it: held from each
// sample to the next. Before the log the valves are taken as settled for its
// first command, unless the log starts at that command's step: the first
// command is not 0 (beyond the logger's 0.01 V), the rod has not moved 0.1 mm
// by kStepRest_s, and the chamber the command charges (1 for u > 0) is not
// yet at the supply (below p_atm + 0.9 (p_s - p_atm)). Then the command
// before the log is the opposite one, -u, where the chamber it discharges is
// at the supply (the rod was driven the other way), else 0 (the valves
// closed): a rig that starts logging as it gives the command. Settled for the
// step's command instead, the valves' lagged gains started fully open and the
// first leg ran too fast (a 0.5 kg unit "not explained" at 1.3e5 per
// residual, against 1.12 with a 0.1 s lead at u = 0). `logged_before_V`: the
// command logged just before the run, when the run is a piece of a longer
// log (PieceStarts); the same command as the piece's first, the valves were
// settled for it.
constexpr double kStepRest_s = 0.005;
constexpr double kCommandNoise_V = 0.01;  // a logger's noise on the command is not a change
constexpr double kMovedAtStart_m = 1e-4;  // a rod that moves this far at a log's start moves
CommandSignal LoggedCommand(const Trajectory& measured, const RigConstants& rig,
                            std::optional<double> logged_before_V = std::nullopt);

// Where a logged run is cut into pieces, each simulated from its own logged
// start with its own command (LoggedCommand of the piece): after an interval
// over kSamplingGapIntervals times the median (log_notes.h) that lasts
// kLoggerPause_s or more (the logger paused, the rig went on), or across
// which a held command stepped (when, the log does not say). Held across
// such a pause, the command before it drove a simulation that the rod did
// not follow: a stroke log with 1.2 s of rows missing mid-stroke left the
// refinement "not explained" at 1.2e6 per residual with q_max 2.7 times the
// truth. A shorter gap with the command held, or in a command that is not
// held (a ramp, a sine), is no cut: the simulation holds the command across
// it. The first sample of every piece, in order; {0} for a run without one.
constexpr double kLoggerPause_s = 0.1;
std::vector<std::size_t> PieceStarts(const Trajectory& measured);

// The samples [begin, end) of a run.
Trajectory Slice(const Trajectory& run, std::size_t begin, std::size_t end);

// Where the logs show the rod pressed against an end stop: at rest (at least
// kMinStopRestSamples within kStopRestBand) within 1 mm of a stop, the
// chambers pushing it there with at least half the force the supply can give
// on the rod side, (p_s - p_a) A2 / 2 (more than any friction of the fleet;
// gravity counted). A transducer zeroed by hand reads such rests some tenths
// of a millimetre off +-half_stroke, and a simulation that clamps the rod at
// the manifest's stroke cannot follow that (0.2 mm: a 0.5 kg unit "not
// explained" at 338 per residual). The offset is the mean of the two stops'
// median rests (the one stop's where only one is seen); taken where it is at
// least kMinPositionZero_m, below that 0 (a rest's noise and ADC step).
constexpr int kMinStopRestSamples = 20;
constexpr double kStopRestBand_m = 60e-6;
constexpr double kMinPositionZero_m = 50e-6;
struct PositionZero {
  double offset_m = 0;             // subtracted from the logged x; 0: none taken
  int rests[2] = {0, 0};           // at the retracted and the extended stop
  double from_stop_m[2] = {0, 0};  // their median's distance from the stop (logged - stop)
  // One line for a report when rests were read ("position zero: the rod
  // rests +0.200 mm from the retracted stop (12 rests) and +0.200 mm from the
  // extended stop (9 rests): x read 0.200 mm lower (a transducer's zero)");
  // empty when no rest at a stop was logged.
  std::string note;
};
PositionZero ReadPositionZero(const Unit& unit);

// e.AsTrajectory() with its x read through `zero` (ReadPositionZero of its
// unit, read once for all of the unit's runs): what the refinement and
// validation compare simulations with.
Trajectory LoggedTrajectory(const Experiment& e, const PositionZero& zero);

// A simulated run as the rig's instruments would have logged it: each
// channel (x, p1, p2, q1, q2) through the lag the manifest declares for it.
void ApplyDeclaredLags(const Manifest& manifest, Trajectory* run);

}  // namespace pneumaid
