// The noise of a unit's channel: what the manifest declares under `sensors`,
// else an estimate from the unit's own logs of that column. `sensors` is
// optional in pneumaid-rig/1 (a channel without an entry is "of unknown
// noise"), so every fit and report reads a channel's noise here, the one home
// of that rule, instead of choosing a fallback of its own.
#pragma once

#include <string>
#include <vector>

#include "pneumaid/io/rig_data.h"

namespace pneumaid {

struct ChannelNoise {
  double sigma = 0;         // noise std in SI units of the column as read; 0: none to be had
  bool declared = false;    // from the manifest's `sensors`; false: estimated from the logs
  double quantum = 0;       // the logs' ADC step when they lie on one (estimated only), else 0
  std::size_t samples = 0;  // the logged samples the estimate read (0 when declared)
};

// A column's noise estimated from its samples alone: the robust spread of the
// fourth differences (a slow signal cancels; a transient, a step or an impact
// is an outlier to a trimmed mean; a signal at rest more than half the time
// is scaled by its moves), at least the rounding of an ADC step (q / sqrt 12)
// when the readings lie on one (99 % of the steps, ten single steps at
// least), and at least 1e-6 of the largest reading (about six significant
// digits written). Within 15 % of sqrt(sigma^2 + q^2 / 12) but where the noise
// is a small fraction of the step (the rounding of a resting signal is then a
// fixed offset that the logs cannot show). Where the signal is not smooth at
// the sampling rate (a light rod's slips at 250 Hz) the spread is the
// signal's: where the log's quiet stretches (blocks of 64 samples whose
// spread is within twice the 10th percentile's, their differences pooled)
// show less than half of it, their noise is taken instead, within 5 % when a
// third of the log is quiet. 0 for fewer than 5 samples or a column that
// never changes. `times`, when given, holds each column's sample times (null
// or missing: uniform): where they lie on no uniform grid (UniformPeriod 0:
// a clock that keeps no time, or one that lost rows) the differences are
// divided by the logged times (a smooth signal then cancels as well).
ChannelNoise EstimateNoise(const std::vector<const std::vector<double>*>& columns,
                           const std::vector<const std::vector<double>*>& times = {});

// The noise `manifest` declares for `column`, or the estimate from `logs` (the
// column's samples in some of the unit's logs, sampled at `times`).
ChannelNoise NoiseOf(const Manifest& manifest, const std::string& column,
                     const std::vector<const std::vector<double>*>& logs,
                     const std::vector<const std::vector<double>*>& times = {});

// NoiseOf the column, estimated from every log of the unit that has it.
ChannelNoise NoiseOf(const Unit& unit, const std::string& column);

// NoiseOf(unit, column).sigma.
double NoiseSigma(const Unit& unit, const std::string& column);

// A declared noise whose logs show more than this many times as much: the
// declaration is likely wrong (a datasheet's figure, another range), and a
// fit weighted by it cannot pass the verdict. Reported, not overridden.
constexpr double kDeclaredNoiseContradicted = 2.0;

// One line for a report on the noise of `columns` that the unit logs: the
// undeclared ones with their estimates ("noise not declared, estimated from
// the logs: x 5.2e-06 m, p1 310 Pa"), then the declared ones whose logs'
// quietest stretches show more than kDeclaredNoiseContradicted times as much
// ("declared noise below what the logs show: p1 100 Pa declared, the logs'
// quietest stretches 227 ..."; a floor, not EstimateNoise: at 250 Hz a light
// rod's slips are not smooth at the sampling rate and would pass for noise);
// empty when neither.
std::string ChannelNoiseNote(const Unit& unit, const std::vector<std::string>& columns);

}  // namespace pneumaid
