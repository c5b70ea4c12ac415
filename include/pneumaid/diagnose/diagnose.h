// The discrepancy workflow: where a parameter set and a unit's logs disagree,
// which effect of the catalog (effects.h) explains it, that effect fitted and
// added, and the gap before and after. docs/diagnose.md gives the method and
// the decision rule.
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "pneumaid/ident/fit_result.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/model/parameters.h"
#include "pneumaid/validate/validate.h"

namespace pneumaid {

// A batch's resume stamp holds every field that changes a diagnosis
// (src/batch/batch.cpp, OptionsFingerprint): a new one belongs there too.
struct DiagnoseOptions {
  // At most this many effects are added, one per iteration.
  int max_effects = 2;
  // Candidate effects; empty: every catalog effect the parameter set lacks.
  std::vector<std::string> effects;
  // Candidate fits run in parallel on this many threads (each fit one thread).
  int threads = 1;
  // Solver iterations per candidate fit.
  int max_iterations = 25;
  // The decision rule (docs/diagnose.md). A candidate is named only when,
  // on the runs held back from its fit, its cost (each channel's mean square
  // in units of the current model's own mean square, summed over every
  // channel) is below the refitted base model's by at least this fraction,
  // pooled over the folds ...
  double min_held_back_gain = 0.10;
  // ... and at least this share of the held-back (fold, channel) mean
  // squares are smaller than the refitted base model's ...
  double min_improved_share = 0.6;
  // ... and at least this share of its gain lies in the channels it can
  // change (a measurement effect: its instrument's) ...
  double min_signature_share = 0.5;
  // ... and the gap it closes is above the noise: some channel's mean square
  // with the base model exceeds the noise variance (NoiseOf: declared, or
  // estimated from the logs) by this factor.
  double min_gap_over_noise = 4.0;
  // Windows for "where": their length, and how many of the worst are listed.
  double window_s = 0.2;
  int worst_windows = 5;
  // The first stretch after a command change counts as its own regime.
  double after_change_s = 0.1;
  // Cooperative stop (a batch unit's time limit): every simulation checks it.
  const std::atomic<bool>* stop = nullptr;
  // Optional progress lines (no printing from the library).
  std::function<void(const std::string&)> log;

  bool IsValid(std::string* error) const;
};

// One channel's residual in one regime, pooled over the runs.
struct RegimeResidual {
  std::string channel, regime;
  long samples = 0;
  double rmse = 0;                // SI
  double mean = 0;                // SI, measured - simulated (the sign of the gap)
  double reduced_chi_square = 0;  // mean square / noise variance (0: no noise to be had)
};

struct ResidualWindow {
  std::string run, channel;
  double from_s = 0, to_s = 0;
  double rmse = 0;  // SI
  double mean = 0;  // SI
};

// "Where": every run simulated from its logged start and compared.
struct DiscrepancyMap {
  std::vector<RegimeResidual> regimes;  // every channel x regime with samples
  std::vector<ResidualWindow> worst;    // worst windows, in units of the channel's noise
  std::map<std::string, double> rmse;   // per channel, pooled over the runs (SI)
  std::map<std::string, double> noise;  // noise sigma per channel (SI, NoiseOf; 0: none)
};

// One candidate effect, fitted and scored.
struct CandidateScore {
  std::string effect;
  FitResult fit;                // on all runs: the effect's parameters and the base's it frees
  double train_gain = 0;        // relative cost drop on the fitted runs, pooled over folds
  double held_back_gain = 0;    // relative cost drop on the held-back runs, pooled (the rule's)
  double own_channel_gain = 0;  // the same in the channels it can change (reported)
  double worst_fold_gain = 0;
  std::vector<double> fold_gains;  // held-back gain of each fold (its runs held back)
  double improved_share = 0;       // of the held-back (fold, channel) mean squares, improved
  std::map<std::string, double> channel_gain;  // held-back, per channel (relative)
  double signature_share = 0;                  // of the held-back gain, in its channels
  double bic_change = 0;                       // for reference only (docs/diagnose.md)
  std::vector<std::string> moved_base;         // base coefficients moved beyond tolerance
  bool significant = false;
  std::string verdict;  // why (not) named
};

struct DiagnoseIteration {
  DiscrepancyMap where;                                   // with the model before this iteration
  std::vector<CandidateScore> ranking;                    // best first
  std::string named;                                      // the effect added, or empty
  std::map<std::string, double> rmse_before, rmse_after;  // per channel, pooled (SI)
};

struct DiagnoseResult {
  std::vector<DiagnoseIteration> iterations;
  std::vector<std::string> named_effects;  // in the order added
  Parameters params;                       // the augmented set (the input when none named)
  ValidationReport before, after;          // every simulable run, first and last model
  std::string conclusion;                  // one paragraph: what was found
  std::string MarkdownReport() const;
  std::string BriefReport() const;
};

// The catalog effects a parameter set lacks and could gain, diagnose's
// candidates by default (pipeline_lag only when the set has no tube lag).
std::vector<std::string> AbsentEffects(const Parameters& params);

// Those of `effects` that are not among AbsentEffects(params), in their
// order: a candidate the set has already (a batch's unit whose refinement
// added stick_creep, for one).
std::vector<std::string> PresentEffects(const std::vector<std::string>& effects,
                                        const Parameters& params);

// Whether every one of `effects` is among AbsentEffects(params); else
// `error` names the first that is not ("effects: 'valve_lag' is already in
// the <set_name>"). Diagnose's rule for its candidates, which a batch also
// applies to its prior before any unit.
bool EffectsAbsent(const std::vector<std::string>& effects, const Parameters& params,
                   const std::string& set_name, std::string* error);

// Throws InputError for bad options, an unknown or present effect, or a unit
// without simulable runs.
DiagnoseResult Diagnose(const Parameters& params, const Unit& unit, const DiagnoseOptions& options);

// The pneumaid-report/1 JSON of a diagnose run (docs/params-format.md).
std::string DiagnoseToJson(const DiagnoseResult& result);

// The effects a diagnose run of unit `unit` (its manifest's id) named, in the
// order added, read back from its pneumaid-report/1 JSON file. InputError
// (file, line) when it is not one, or one of another unit.
std::vector<std::string> ReadNamedEffects(const std::string& report_json_path,
                                          const std::string& unit);

}  // namespace pneumaid
