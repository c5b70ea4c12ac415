// `identify`: a unit's logs -> a parameter set. Each component is a fit of
// its own; what is not fitted (not requested, or no log of its kind) comes
// from the prior, and the report says which is which and why.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "pneumaid/ident/friction_fit.h"
#include "pneumaid/ident/pipeline_fit.h"
#include "pneumaid/ident/valve_fit.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/model/parameters.h"

namespace pneumaid {

enum class Component { kValve, kPipeline, kFriction };

const char* ToString(Component component);

struct IdentifyOptions {
  // Components to fit (default: all).
  std::set<Component> components = {Component::kValve, Component::kPipeline, Component::kFriction};
  // The caller named `components`: a named component whose kind of log the
  // unit lacks is an InputError (otherwise the prior, reported as such).
  bool components_explicit = false;
  ValveFitOptions valve;
  PipelineFitOptions pipeline;  // initial_delta_per_s is taken from the prior
  FrictionFitOptions friction;
  std::string tool_version = "unknown";  // for provenance
  std::string date;                      // ISO 8601, for provenance

  bool IsValid(std::string* error) const;
};

struct IdentifyReport {
  ValveFitResult valve;
  PipelineFitResult pipeline;
  FrictionFitResult friction;
  std::vector<std::string> fitted;  // parameter paths
  std::vector<std::string> priors;  // parameter paths taken from the prior, with why
  // What the logs say of the prior's model choices, which no fit makes
  // ("valve.branch: the prior's increasing; ... the choice matters for these
  // logs"); empty when nothing.
  std::vector<std::string> notes;
  // The channels whose noise the unit does not declare, with the estimates
  // from the logs that the fits used, and the declared ones whose logs show
  // far more (ChannelNoiseNote); empty when neither.
  std::string noise_note;
  // Each component fit that ran and did not converge, or whose misfit its
  // verdict does not accept ("pipeline: the model does not explain these
  // logs (why)", "friction: NOT converged (why)"); empty when every one did.
  // Its values are written all the same, and the provenance says so (status
  // per fit); the CLI then exits 3.
  std::vector<std::string> NotAccepted() const;
  std::string BriefReport() const;
};

// The unit's conditions and geometry (manifest), fitted components, priors
// for the rest, uncertainty and provenance. Throws InputError when the
// options are not valid or a component named explicitly has no log to fit,
// FitError when the identified set is not physical. `report` may be null.
Parameters Identify(const Unit& unit, const Parameters& prior, const IdentifyOptions& options,
                    IdentifyReport* report);

}  // namespace pneumaid
