// How a logged run is set up for simulation: the one home of "which
// constants win", the state a run starts from and what its meters add.
// Validate, identify and refine all ask here; none applies conditions on its
// own.
#pragma once

#include "pneumaid/io/rig_data.h"
#include "pneumaid/model/parameters.h"
#include "pneumaid/sim/simulate.h"
#include "pneumaid/trajectory.h"

namespace pneumaid {

// The parameter set under a log's conditions ("which constants win"): supply
// and atmospheric pressure, gas temperature, orientation and load mass from the
// manifest; geometry from the parameter set. Geometry the manifest states
// (bore, rod, stroke, dead volumes) that disagrees by more than 1 % is an
// InputError naming the manifest.
Parameters WithRigConditions(const Parameters& params, const Unit& unit);

// The unit's own constants over `params` (what identify starts from): the
// conditions above, and the unit's id, gas, geometry and tube length as its
// manifest states them.
Parameters WithUnitConstants(const Parameters& params, const Unit& unit);

// The state a logged run starts from: the mean of its leading samples while
// the command has not yet changed by more than 0.01 V (at most 50); its first sample when the rod
// already moves. The position is clamped to the stroke (+-half_stroke_m): a rod
// resting on an end stop reads up to a few noise sigmas beyond it.
// `samples_averaged`, if given, receives how many samples the start is the
// mean of (1 for a moving start).
InitialState LoggedInitialState(const Trajectory& measured, double half_stroke_m,
                                int* samples_averaged = nullptr);

// A simulated run as the rig's instruments would have logged it: each
// channel (x, p1, p2, q1, q2) through the lag the manifest declares for it.
void ApplyDeclaredLags(const Manifest& manifest, Trajectory* run);

}  // namespace pneumaid
