// identify on a synthetic unit: what is fitted, what comes from the prior,
// uncertainty and provenance.
#include "pneumaid/ident/identify.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <map>
#include <string>

#include "../synth/synth_test_util.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/provenance.h"
#include "pneumaid/synth/synthetic_rig.h"

namespace pneumaid {
namespace {

const std::string kUnit = std::string(PNEUMAID_SOURCE_DIR) + "/datasets/paper-rig";

bool Lists(const std::vector<std::string>& items, const std::string& prefix) {
  return std::any_of(items.begin(), items.end(),
                     [&](const std::string& item) { return item.rfind(prefix, 0) == 0; });
}

TEST(IdentifyTest, FitsTheValveAndSaysWhatCameFromThePrior) {
  const Unit unit = ReadUnit(kUnit);
  Parameters prior;
  prior.valve.increasing.q_max_kg_per_s *= 1.3;  // a poor prior: the fit must move it
  IdentifyReport report;
  const Parameters p = Identify(unit, prior, IdentifyOptions{}, &report);
  EXPECT_NEAR(p.valve.increasing.q_max_kg_per_s, 9.25e-5, 0.01 * 9.25e-5);
  EXPECT_TRUE(Lists(report.fitted, "valve.increasing.q_max"));
  EXPECT_TRUE(Lists(report.fitted, "friction.positive.Fs"));
  EXPECT_TRUE(Lists(report.fitted, "friction.negative.vs"));
  EXPECT_GT(p.uncertainty.at("friction.negative.b"), 0.0);
  EXPECT_TRUE(Lists(report.fitted, "pipeline.delta"));
  EXPECT_NEAR(p.pipeline.delta_per_s, 8.0, 0.05 * 8.0);
  EXPECT_EQ(p.pipeline.delta_by_length.size(), 4u);
  EXPECT_GT(p.uncertainty.at("pipeline.delta"), 0.0);
  EXPECT_GT(p.uncertainty.at("valve.decreasing.d"), 0.0);
  EXPECT_EQ(p.unit, "paper-rig");
  EXPECT_NE(p.provenance_yaml.find(unit.experiments.front().sha256), std::string::npos);
  // The result is a valid params-v1 document that reads back.
  const Parameters back = ParamsFromYaml(ParamsToYaml(p), "identified");
  EXPECT_EQ(back.valve.decreasing.a, p.valve.decreasing.a);
}

// valve.branch is the prior's: where the fitted branches differ and a
// stroke or validation log closes a valve pair part way (a held opening,
// then a smaller one of the same sign), the report says that the choice
// matters. The bundled unit's strokes step from 0 or change sign; its rich
// validation profile closes part way; one leg of a stroke log changed from
// 0.6 V to 0.4 V half way adds one. Not said with a prior of hysteresis.
TEST(IdentifyTest, SaysWhenTheValveBranchOfThePriorMatters) {
  Unit unit = ReadUnit(kUnit);
  IdentifyOptions options;
  options.components = {Component::kValve};
  IdentifyReport report;
  const auto closings = [&report]() -> int {
    for (const std::string& p : report.notes) {
      if (p.rfind("valve.branch: the prior's increasing; the branches fitted differ by up to", 0))
        continue;
      const auto at = p.find("close a valve pair part way ");
      return at == std::string::npos ? -1 : std::stoi(p.substr(at + 28));
    }
    return 0;
  };
  Unit strokes = unit;
  strokes.experiments.erase(std::remove_if(strokes.experiments.begin(), strokes.experiments.end(),
                                           [](const Experiment& e) {
                                             return e.entry.kind == ExperimentKind::kValidation;
                                           }),
                            strokes.experiments.end());
  Identify(strokes, Parameters{}, options, &report);
  EXPECT_EQ(closings(), 0) << report.BriefReport();
  Identify(unit, Parameters{}, options, &report);
  const int profile = closings();
  EXPECT_GT(profile, 0) << report.BriefReport();
  for (Experiment& e : unit.experiments) {
    if (e.entry.id != "stroke-060") continue;
    const std::vector<double>& t = e.columns.at("t");
    std::vector<double>& u = e.columns.at("u");
    for (std::size_t i = 0; i < t.size(); ++i) {
      if (t[i] >= 0.3 && t[i] < 0.506) u[i] = 0.4;  // in the first leg at 0.6 V
    }
  }
  Identify(unit, Parameters{}, options, &report);
  EXPECT_EQ(closings(), profile + 1) << report.BriefReport();
  Parameters hysteresis;
  hysteresis.valve.branch = ValveBranchMode::kHysteresis;
  Identify(unit, hysteresis, options, &report);
  EXPECT_TRUE(report.notes.empty()) << report.BriefReport();
}

// An effect of the prior is kept and listed as the prior's; one that acts on
// friction (a rod that creeps, friction that scales with the pressures) is
// named with what it means for the friction fitted without it.
TEST(IdentifyTest, ThePriorsEffectsAreListedAsFromThePrior) {
  const Unit unit = ReadUnit(kUnit);
  Parameters prior;
  prior.effects["stick_creep"]["v"] = 1e-4;
  prior.effects["valve_lag"]["tau"] = 0.004;
  prior.effects["friction_pressure"]["kp"] = 1e-7;
  IdentifyReport report;
  const Parameters p = Identify(unit, prior, IdentifyOptions{}, &report);
  EXPECT_EQ(p.effects, prior.effects);
  for (const char* effect : {"stick_creep.v", "friction_pressure.kp"}) {
    EXPECT_TRUE(Lists(report.priors, std::string("effects.") + effect +
                                         " (an effect of the prior; the component fits do not "
                                         "model it: friction.* were fitted without it, to the "
                                         "paper's law with exact stick)"))
        << effect << "\n"
        << report.BriefReport();
  }
  EXPECT_TRUE(Lists(report.priors,
                    "effects.valve_lag.tau (an effect of the prior; the component "
                    "fits do not model it)"))
      << report.BriefReport();
}

// A coefficient a fit that ran held (here u_sat, kept at the prior's) is
// named with why in the provenance's `held`, which the report reads; the
// coefficients the fits determined and the components not fitted are not.
TEST(IdentifyTest, TheProvenanceNamesTheHeldCoefficientsWithWhy) {
  const Unit unit = ReadUnit(kUnit);
  IdentifyOptions options;
  options.valve.fit_u_sat = false;
  options.components = {Component::kValve};
  IdentifyReport report;
  const Parameters p = Identify(unit, Parameters{}, options, &report);
  const std::map<std::string, std::string> held = ProvenanceStrings(p.provenance_yaml, "", "held");
  for (const FittedCoefficient& c : report.valve.coefficients) {
    if (c.determined()) {
      EXPECT_EQ(held.count(c.path), 0u) << c.path;
    } else {
      ASSERT_EQ(held.count(c.path), 1u) << c.path << "\n" << p.provenance_yaml;
      EXPECT_EQ(held.at(c.path), c.held);
    }
  }
  EXPECT_EQ(held.at("valve.increasing.u_sat"), "fixed at the prior's (fit_u_sat is off)");
  EXPECT_EQ(held.count("friction.positive.Fs"), 0u);  // not requested: no fit ran
}

// A fit that ran and fitted nothing (a tube test whose command never
// changes) names what it held, and why, in the provenance's `held` as well:
// before, only a fit with values did, so the set did not say that its delta
// was the prior's.
TEST(IdentifyTest, AFitThatRanAndFittedNothingNamesWhatItHeld) {
  Protocol protocol;
  protocol.tube_lengths_m = {0.38};
  protocol.pipeline_schedule = {{0.0, 1.0}};
  const Unit unit =
      testing::WriteAndReadUnit(Synthesize(Parameters{}, protocol, 5, "P"), "identify_flat_tube");
  IdentifyOptions options;
  options.components = {Component::kPipeline};
  IdentifyReport report;
  const Parameters p = Identify(unit, Parameters{}, options, &report);
  ASSERT_EQ(report.pipeline.status, FitStatus::kNotFitted);
  const std::map<std::string, std::string> held = ProvenanceStrings(p.provenance_yaml, "", "held");
  ASSERT_EQ(held.count("pipeline.delta"), 1u) << p.provenance_yaml;
  EXPECT_NE(held.at("pipeline.delta").find("pipe-038: "), std::string::npos)
      << held.at("pipeline.delta");
  EXPECT_NE(held.at("pipeline.delta").find("never changes"), std::string::npos)
      << held.at("pipeline.delta");
  EXPECT_EQ(held.count("valve.increasing.q_max"), 0u);  // not requested: no fit ran
}

// The provenance names the unit and its directory as an absolute path (a
// relative one names nothing once the set leaves the shell it was made in).
TEST(IdentifyTest, TheProvenanceNamesTheUnitAndItsAbsoluteDirectory) {
  const Unit unit = ReadUnit(kUnit);
  IdentifyOptions options;
  options.components = {Component::kValve};
  const Parameters p = Identify(unit, Parameters{}, options, nullptr);
  const YAML::Node provenance = YAML::Load(p.provenance_yaml);
  EXPECT_EQ(provenance["unit"].as<std::string>(""), unit.manifest.unit) << p.provenance_yaml;
  const std::filesystem::path directory(provenance["unit_directory"].as<std::string>(""));
  EXPECT_TRUE(directory.is_absolute()) << directory;
  EXPECT_TRUE(std::filesystem::equivalent(directory, unit.directory)) << directory;
}

// A fit that ran out of iterations still gives its best point, and says so:
// in the report's list of fits not converged (the CLI's exit 3) and in the
// provenance's status of that fit; the fits that converged say that too.
TEST(IdentifyTest, AFitThatDidNotConvergeSaysSoInTheReportAndTheProvenance) {
  const Unit unit = ReadUnit(kUnit);
  IdentifyOptions options;
  options.components = {Component::kValve, Component::kFriction};
  IdentifyReport report;
  Parameters p = Identify(unit, Parameters{}, options, &report);
  EXPECT_TRUE(report.NotAccepted().empty()) << report.BriefReport();
  EXPECT_EQ(ProvenanceStrings(p.provenance_yaml, "", "friction").at("status"), "converged");
  options.friction.max_iterations = 1;
  p = Identify(unit, Parameters{}, options, &report);
  ASSERT_EQ(report.NotAccepted().size(), 1u) << report.BriefReport();
  EXPECT_EQ(report.NotAccepted().front().rfind("friction: NOT converged (", 0), 0u)
      << report.NotAccepted().front();
  EXPECT_EQ(ProvenanceStrings(p.provenance_yaml, "", "friction").at("status"), "NOT converged");
  EXPECT_EQ(ProvenanceStrings(p.provenance_yaml, "", "valve_increasing").at("status"), "converged");
}

TEST(IdentifyTest, ComponentsWithoutDataAreRefusedWhenAskedForAndPriorsOtherwise) {
  const Unit unit = ReadUnit(kUnit);
  IdentifyReport report;
  IdentifyOptions options;
  const Parameters defaults;
  Unit no_stroke = unit;
  no_stroke.experiments.erase(
      std::remove_if(no_stroke.experiments.begin(), no_stroke.experiments.end(),
                     [](const Experiment& e) { return e.entry.kind == ExperimentKind::kStroke; }),
      no_stroke.experiments.end());
  options.components = {Component::kFriction};
  options.components_explicit = true;
  EXPECT_THROW(Identify(no_stroke, defaults, options, &report), InputError);
  options.components_explicit = false;
  const Parameters without_strokes = Identify(no_stroke, defaults, options, &report);
  EXPECT_TRUE(Lists(report.priors, "friction.positive.Fs (no stroke experiment)"));
  // The unit logs a valve test: the valve is the prior's because only friction was asked for.
  EXPECT_TRUE(Lists(report.priors, "valve.increasing.a (not requested)"));
  // The report says why in one line per component not fitted (it said "not
  // fitted ()" and listed the valve's branches and no plateaus).
  const std::string brief = report.BriefReport();
  EXPECT_NE(brief.find("Friction fit: not fitted (no stroke experiment)\n"), std::string::npos)
      << brief;
  EXPECT_NE(brief.find("Valve K_vp fit: not fitted (not requested)\n"), std::string::npos) << brief;
  EXPECT_NE(brief.find("Pipeline delta fit: 0 tube logs, not fitted (not requested)\n"),
            std::string::npos)
      << brief;
  EXPECT_EQ(brief.find("()"), std::string::npos) << brief;
  // No confident number from nothing: a prior carries no standard error.
  EXPECT_EQ(without_strokes.uncertainty.count("friction.positive.Fs"), 0u);
  options.components_explicit = true;
  Unit no_valve = unit;
  no_valve.experiments.erase(no_valve.experiments.begin());  // the valve staircase
  options.components = {Component::kValve};
  EXPECT_THROW(Identify(no_valve, defaults, options, &report), InputError);
  options.components_explicit = false;  // by default: the prior, reported as such
  const Parameters p = Identify(no_valve, defaults, options, &report);
  EXPECT_TRUE(Lists(report.priors, "valve.increasing.a (no valve experiment)"));
  EXPECT_NE(report.BriefReport().find("Valve K_vp fit: not fitted (no valve experiment)\n"),
            std::string::npos);
  EXPECT_EQ(p.valve.increasing.a, defaults.valve.increasing.a);
}

}  // namespace
}  // namespace pneumaid
