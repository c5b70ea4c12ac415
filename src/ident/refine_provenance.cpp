#include "refine_provenance.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <set>

#include "../io/provenance_map.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/provenance.h"

namespace pneumaid::refine_internal {
namespace {

// A double as YAML text, whatever the process's locale (yaml-cpp's own
// conversion goes through it): YAML's spellings where it is not finite.
std::string YamlNumber(double value) {
  if (std::isnan(value)) return ".nan";
  if (std::isinf(value)) return value > 0 ? ".inf" : "-.inf";
  return FormatDouble(value);
}

}  // namespace

bool RefinedBefore(const Parameters& start) {
  return HasProvenanceEntry(start.provenance_yaml, "refine");
}

std::string WithRefineEntry(const std::string& provenance, const RefineResult& r,
                            const FitSpec& spec) {
  YAML::Node entry(YAML::NodeType::Map);
  entry["spec"] = spec.source;
  // Numbers as text of their own: yaml-cpp would format them through the
  // process's locale (a host's "1,234" or "0,5").
  entry["cost_before"] = YamlNumber(r.initial_cost);
  entry["cost_after"] = YamlNumber(r.final_cost);
  entry["iterations"] = std::to_string(r.iterations);
  entry["stages"] = std::to_string(r.stages);
  entry["starts"] = std::to_string(r.starts);
  entry["experiments"] = std::to_string(r.fitted.size());
  entry["initial_pressures"] = spec.fit_initial_pressures ? "fit" : "logged";
  // The estimates the verdict holds from, per run: [p1, p2] in Pa absolute
  // (the logged ones leave a worse fit; docs/refinement.md). Of the refined
  // set only.
  if (!r.estimated_starts.empty() && !r.start_written) {
    YAML::Node starts(YAML::NodeType::Map);
    for (const EstimatedStart& e : r.estimated_starts) {
      YAML::Node pair(YAML::NodeType::Sequence);
      pair.push_back(FormatDouble(e.p1_Pa));
      pair.push_back(FormatDouble(e.p2_Pa));
      starts[e.run] = pair;
    }
    entry["initial_pressures_Pa"] = starts;
  }
  entry["status"] = ToString(r.status);
  entry["reduced_chi_square"] = YamlNumber(r.reduced_chi_square);
  entry["acceptable_reduced_chi_square"] = YamlNumber(r.acceptable_reduced_chi_square);
  entry["converged"] = r.explained();
  if (!r.creep_report.empty()) entry["creep_fit"] = r.creep_report;
  if (r.start_written) {
    // What the refinement found, not written: the written set's values are
    // the start's, and so are its words on them (identify's `held`, an
    // earlier refinement's `refine`).
    YAML::Node refined(YAML::NodeType::Map);
    for (const FittedCoefficient& c : r.coefficients) refined[c.path] = YamlNumber(c.value);
    entry["refined"] = refined;
    return WithProvenanceEntry(provenance, "refine_not_written", entry);
  }
  // Fitted, but on a bound of its range: no standard error, so no entry in
  // `uncertainty` (a reader would otherwise take it for the prior's).
  YAML::Node at_bound(YAML::NodeType::Sequence);
  for (const FittedCoefficient& c : r.coefficients)
    if (c.at_bound) at_bound.push_back(c.path);
  // Not determined by the fitted runs, with why: their `uncertainty` is the
  // prior's pull, not the runs' (the report tells them from the fitted).
  YAML::Node held(YAML::NodeType::Map);
  for (const auto& [path, why] : r.Held()) held[path] = why;
  // A set refined before: what that refinement said of a coefficient this one
  // did not free still holds (its value and error are that refinement's).
  std::set<std::string> freed;
  for (const FittedCoefficient& c : r.coefficients) freed.insert(c.path);
  for (const std::string& path : ProvenanceList(provenance, "refine", "at_bound"))
    if (freed.count(path) == 0) at_bound.push_back(path);
  for (const auto& [path, why] : ProvenanceStrings(provenance, "refine", "held"))
    if (freed.count(path) == 0) held[path] = why;
  entry["at_bound"] = at_bound;
  entry["held"] = held;
  // What this refinement freed: a component fit's word on these (identify's
  // `held`) no longer holds, whether or not they got a standard error.
  YAML::Node free(YAML::NodeType::Sequence);
  for (const std::string& path : freed) free.push_back(path);
  entry["free"] = free;
  return WithProvenanceEntry(provenance, "refine", entry);
}

}  // namespace pneumaid::refine_internal
