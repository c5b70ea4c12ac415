// Logs on a uniform clock: the friction fit's replay steps sample by sample,
// so a stroke log that a lossy logger thinned (or stamped with jitter) is
// read on a uniform clock instead.
#pragma once

#include <memory>
#include <vector>

#include "pneumaid/io/rig_data.h"

namespace pneumaid::internal {

// The sampling interval of `t` when every interval is within 1 % of the
// mean, else 0.
double UniformPeriod(const std::vector<double>& t);

// How many whole sampling intervals fit in `duration_s`, and how many it
// takes to cover it, with the round-off of a logged clock forgiven: a
// duration of exactly four intervals is four, whether the interval read off
// the time stamps is a part in 1e9 above or below its nominal value (a
// logger's clock origin moves it that much).
int WholeSamples(double duration_s, double period_s);
int SamplesCovering(double duration_s, double period_s);

// `e` on a uniform clock at its median sampling interval: each column
// interpolated linearly between its samples, the command (`u`) held from
// each sample.
std::shared_ptr<const Experiment> ResampledUniformly(const Experiment& e);

}  // namespace pneumaid::internal
