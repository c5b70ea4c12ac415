// Diagnose (diagnose.h), the candidates: which base coefficients a candidate
// fit frees, each effect's residual signature, and the cross-validated fits
// and scores of the decision rule (docs/diagnose.md).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "discrepancy_map.h"
#include "pneumaid/diagnose/diagnose.h"
#include "pneumaid/ident/fit_spec.h"

namespace pneumaid::diagnose_internal {

// The channels an effect can change: a measurement effect's instrument alone,
// a plant effect's every channel.
std::vector<std::string> SignatureChannels(const std::string& effect);

// The base coefficients the reference fit and every candidate fit free: the
// valve's gain, the tube's lag (when the base has one) and the sliding
// friction of each direction, in a box around their values; with
// `static_friction` also each direction's Fs (the named effect's final fit:
// freeing Fs in the decision lets it absorb a pressure-dependent friction,
// measured: friction_pressure's held-back gain fell from 47 % to 8 %).
std::vector<FreeParameter> BaseParameters(const Parameters& params, bool static_friction = false);

// `params` with `effect` added at `fraction` of its typical size (at least
// its plausible minimum).
Parameters WithEffect(const Parameters& params, const std::string& effect, double fraction = 1.0);

// Starts the logs give a fit beyond the given set (and a candidate's typical
// size), read off runs `runs` only (a fold's training runs), changing only
// what the fit frees (BaseParameters, CandidateParameters; `static_friction`
// alike): the sliding friction (and Fs) from the force balance of the slides
// (FrictionFromSlides; output error through the simulator has narrow basins
// in them under stick-slip), with friction_pressure's kp for that candidate.
// `effect` empty: the base model's own fit, which gets the same starts as
// the candidates, so that a candidate's gain is never a better start's.
// Empty when the runs do not give one.
std::vector<Parameters> DataStarts(const Parameters& reference, const std::string& effect,
                                   const Unit& unit, const std::vector<std::string>& runs,
                                   bool static_friction = false);

// The free parameters of a candidate: the effect's, within its plausible
// range, then the base's.
std::vector<FreeParameter> CandidateParameters(const Parameters& with_effect,
                                               const std::string& effect,
                                               bool static_friction = false);

// A fit spec of `parameters` on runs `fit`, every channel weighted by
// `scale` (its variance with the base model, at least the noise's).
FitSpec MakeSpec(const std::vector<FreeParameter>& parameters, const std::vector<std::string>& fit,
                 const std::map<std::string, double>& scale, const DiagnoseOptions& options,
                 const std::string& name);

// Folds of the runs for held-back scoring: with k runs, k folds of one run
// each (at most 3 folds, runs dealt round-robin); each fold's runs are held
// back from its fits.
std::vector<std::vector<std::string>> Folds(const std::vector<std::string>& runs);

// Base coefficients that `candidate` moved beyond the identification
// tolerances from `reference` (by path, with both values).
std::vector<std::string> MovedBase(const Parameters& reference, const Parameters& candidate,
                                   const std::vector<FreeParameter>& base);

}  // namespace pneumaid::diagnose_internal
