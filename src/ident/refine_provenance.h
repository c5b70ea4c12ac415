// A refinement's entry in the provenance of the set it writes, and what an
// earlier one says of a start (refine.h; docs/refinement.md lists the
// fields).
#pragma once

#include <string>

#include "pneumaid/ident/fit_spec.h"
#include "pneumaid/ident/refine.h"
#include "pneumaid/model/parameters.h"

namespace pneumaid::refine_internal {

// Whether the set was already refined: its standard errors then come from
// a fit of the same runs, not from the component fits' own experiments.
bool RefinedBefore(const Parameters& start);

// `provenance` with this refinement's entry (replacing any earlier one of its
// name: a mapping has one key of a name), in flow style: `refine` for a
// refined set; `refine_not_written` where the start is written instead
// (RefineResult::start_written), which leaves the start's own entries, and
// with them what the written values are, as they were.
std::string WithRefineEntry(const std::string& provenance, const RefineResult& r,
                            const FitSpec& spec);

}  // namespace pneumaid::refine_internal
