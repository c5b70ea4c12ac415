// One branch of K_vp fitted to its plateaus at a given u_sat (FitValve's
// step, and the saturation search's for each split it tries).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "pneumaid/ident/valve_fit.h"

namespace pneumaid::internal {

constexpr int kBranchParameters = 5;  // q_max, a, b, c, d

// q_max, a, b, c, d of a branch.
std::array<double, kBranchParameters> Pack(const KvpBranchParams& p);

// The branch fitted to `plateaus` at the prior's u_sat, from the prior; the
// coefficients named `prefix`.q_max, ... A branch the plateaus cannot
// determine is not fitted and keeps the prior, with why.
BranchFit FitBranch(const std::vector<const ValvePlateau*>& plateaus, const KvpBranchParams& prior,
                    const std::string& prefix, const ValveFitOptions& options);

}  // namespace pneumaid::internal
