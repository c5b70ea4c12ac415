#pragma once

// The refinement's creep fit (RefineOptions::fit_stick_creep): the stick's
// creep speed fitted after the paper model's, kept where the runs show it.

#include <string>

#include "pneumaid/ident/fit_spec.h"
#include "pneumaid/ident/refine.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/model/parameters.h"

namespace pneumaid::refine_internal {

// From `paper` (the fit of the spec's parameters from `start`): each creep
// speed of options.stick_creep_profile held while the spec's last stage is
// fitted again from paper's set (no screens: it starts in the paper fit's
// basin), then effects.stick_creep.v freed from the best. The creep fit is
// returned, in the paper fit's frame (its start's costs, held-out runs
// before and coefficient starts; its reports; held_out_after is the
// caller's to fill: the inner fits validate nothing), when it is Better
// than paper and its verdict measure is at most
// options.stick_creep_keep_ratio of paper's (or it is explained and paper is
// not); otherwise paper. Either way creep_report says what was tried, or why
// nothing was.
RefineResult WithStickCreep(RefineResult paper, const Parameters& start, const Unit& unit,
                            const FitSpec& spec, const RefineOptions& options);

// The creep fit's line where it is not run: why it does not apply to this
// refinement, or, where it would, `because`.
std::string CreepNotRunReport(const RefineResult& paper, const Parameters& start,
                              const FitSpec& spec, const RefineOptions& options,
                              const std::string& because);

// The options of the creep fit's inner fits, from the refinement's: its
// last stage alone in the paper fit's basin (none of the searches for another
// basin, no creep fit of their own), their refined sets returned whatever
// their verdict (they are compared, not written).
RefineOptions InnerOptions(const RefineOptions& options);

// A creep fit kept with v held at a profile point (the fit with it freed
// ended higher): v listed among its coefficients as held, by name, with
// `why`; no standard error, the others' errors conditional on it.
void ListHeldCreepSpeed(double v_m_per_s, const std::string& why, RefineResult* creep);

}  // namespace pneumaid::refine_internal
