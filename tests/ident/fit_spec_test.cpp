// The fit spec format (pneumaid-fit/1): the shipped specs parse; every kind of
// mistake is one InputError naming the file, the line and what was expected.
#include "pneumaid/ident/fit_spec.h"

#include <gtest/gtest.h>

#include "pneumaid/io/input_error.h"

namespace pneumaid {
namespace {

TEST(FitSpecTest, TheDefaultSpecFreesTenParametersInTwoStages) {
  const FitSpec spec = LoadFitSpec(std::string(PNEUMAID_SOURCE_DIR) + "/configs/fit-default.yaml");
  ASSERT_EQ(spec.parameters.size(), 10u);
  EXPECT_EQ(spec.parameters[0].path, "pipeline.delta");
  EXPECT_EQ(spec.parameters[0].scale, ParameterScale::kLog);
  EXPECT_EQ(spec.parameters[2].scale, ParameterScale::kLinear);
  ASSERT_EQ(spec.stages.size(), 2u);
  EXPECT_EQ(spec.stages[0].parameters.size(), 2u);
  EXPECT_TRUE(spec.stages[1].parameters.empty());  // all
  EXPECT_EQ(spec.channels.size(), 3u);
  EXPECT_EQ(spec.fit, std::vector<std::string>{"stroke"});
  EXPECT_EQ(spec.hold_out, std::vector<std::string>{"validation"});
}

TEST(FitSpecTest, TheFromScratchSpecReplaysFrictionThenShootsThenFitsAll) {
  const FitSpec spec =
      LoadFitSpec(std::string(PNEUMAID_SOURCE_DIR) + "/configs/fit-from-scratch.yaml");
  ASSERT_EQ(spec.stages.size(), 3u);
  EXPECT_TRUE(spec.stages[0].friction_replay);
  EXPECT_TRUE(spec.stages[1].windows);
  EXPECT_EQ(spec.stages[1].parameters.size(), 2u);
  EXPECT_FALSE(spec.stages[2].windows || spec.stages[2].friction_replay);
}

TEST(FitSpecTest, ChannelsTakeASigmaAndAWeight) {
  const FitSpec spec = ParseFitSpec(R"(format: pneumaid-fit/1
parameters: {friction.positive.Fs: {min: 0, max: 50}}
channels: {x: {sigma: 1.0e-5, weight: 2}, p1: {}}
multistart: 4
seed: 9
)",
                                    "s.yaml");
  EXPECT_DOUBLE_EQ(spec.channels.at("x").sigma, 1e-5);
  EXPECT_DOUBLE_EQ(spec.channels.at("x").weight, 2.0);
  EXPECT_DOUBLE_EQ(spec.channels.at("p1").sigma, 0.0);  // the manifest's
  EXPECT_EQ(spec.multistart, 4);
  EXPECT_EQ(spec.seed, 9u);
  EXPECT_TRUE(spec.fit_initial_pressures);  // the default
  // A bare channel, in a set or with nothing after it, takes the defaults.
  for (const char* channels : {"channels: {x, p1}\n", "channels:\n  x:\n  p1:\n"}) {
    const FitSpec bare = ParseFitSpec(
        std::string("format: pneumaid-fit/1\nparameters: {pipeline.delta: {min: 1, max: 9}}\n") +
            channels,
        "s.yaml");
    ASSERT_EQ(bare.channels.size(), 2u) << channels;
    EXPECT_EQ(bare.channels.at("p1").weight, 1.0);
  }
}

// A seed past an int's range is read whole (it once passed the reader's
// check and was then cast to int); one past the stated range is refused.
TEST(FitSpecTest, ASeedIsReadWholeUpToItsStatedRange) {
  const char* head = "format: pneumaid-fit/1\nparameters: {pipeline.delta: {min: 1, max: 9}}\n";
  EXPECT_EQ(ParseFitSpec(std::string(head) + "seed: 4000000000\n", "s.yaml").seed, 4000000000u);
  EXPECT_EQ(ParseFitSpec(std::string(head) + "seed: 1000000000000000\n", "s.yaml").seed,
            1000000000000000u);
  EXPECT_THROW(ParseFitSpec(std::string(head) + "seed: 1000000000000001\n", "s.yaml"), InputError);
}

TEST(FitSpecTest, InitialPressuresAreFittedOrTakenAsLogged) {
  for (const auto& [how, fitted] : {std::make_pair("logged", false), std::make_pair("fit", true)}) {
    const FitSpec spec = ParseFitSpec(std::string("format: pneumaid-fit/1\n"
                                                  "parameters: {pipeline.delta: {min: 1, max: 9}}\n"
                                                  "initial_pressures: ") +
                                          how + "\n",
                                      "s.yaml");
    EXPECT_EQ(spec.fit_initial_pressures, fitted) << how;
  }
}

struct BadSpec {
  const char* what;
  const char* text;
  int line;
  const char* mentions;
};

class FitSpecBadInputTest : public ::testing::TestWithParam<BadSpec> {};

TEST_P(FitSpecBadInputTest, OneMessageNamingFileLineAndExpectation) {
  const BadSpec& bad = GetParam();
  try {
    ParseFitSpec(bad.text, "bad.yaml");
    ADD_FAILURE() << bad.what << ": accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "bad.yaml") << bad.what;
    EXPECT_EQ(e.line(), bad.line) << bad.what << ": " << e.message();
    EXPECT_NE(e.message().find(bad.mentions), std::string::npos) << bad.what << ": " << e.message();
  }
}

INSTANTIATE_TEST_SUITE_P(
    Mistakes, FitSpecBadInputTest,
    ::testing::Values(
        BadSpec{"format", "format: pneumaid-fit/2\nparameters: {}\n", 1, "pneumaid-fit/1"},
        BadSpec{"unknown key", "format: pneumaid-fit/1\nparameter: {}\n", 2, "unknown key"},
        // A key with nothing after it: its own line, not the next key's.
        BadSpec{"empty value", "format: pneumaid-fit/1\nparameters:\nchannels: {x: {}}\n", 2,
                "parameters: expected a value after the key"},
        BadSpec{"unknown path",
                "format: pneumaid-fit/1\nparameters:\n  friction.positive.Fz: {min: 0, max: 1}\n",
                3, "friction.positive.Fz"},
        BadSpec{"min above max",
                "format: pneumaid-fit/1\nparameters:\n  pipeline.delta: {min: 9, max: 1}\n", 3,
                "min < max"},
        BadSpec{"bound outside the physical range",
                "format: pneumaid-fit/1\nparameters:\n  friction.positive.Fs: {min: -1, max: 9}\n",
                3, "bounds must each be a finite number"},
        BadSpec{"log scale through zero",
                "format: pneumaid-fit/1\nparameters:\n"
                "  friction.positive.Fd: {min: 0, max: 9, scale: log}\n",
                3, "min > 0"},
        BadSpec{"an effect's bound outside what the model accepts",  // v = 0: no creep width
                "format: pneumaid-fit/1\nparameters:\n"
                "  effects.stick_creep.v: {min: 0, max: 1.0e-3}\n",
                3, "parameters.effects.stick_creep.v: bounds must each be a finite number"},
        BadSpec{"an effect the catalog does not have",
                "format: pneumaid-fit/1\nparameters:\n"
                "  effects.stick_creap.v: {min: 1.0e-5, max: 1.0e-3}\n",
                3, "unknown parameter 'effects.stick_creap.v'"},
        BadSpec{"scale name",
                "format: pneumaid-fit/1\nparameters:\n"
                "  friction.positive.Fd: {min: 0, max: 9, scale: cubic}\n",
                3, "linear | log"},
        BadSpec{"unknown channel",
                "format: pneumaid-fit/1\nparameters: {pipeline.delta: {min: 1, max: 9}}\n"
                "channels: {v: {}}\n",
                3, "unknown key 'channels.v'"},
        BadSpec{"negative sigma",
                "format: pneumaid-fit/1\nparameters: {pipeline.delta: {min: 1, max: 9}}\n"
                "channels:\n  x: {sigma: -1}\n",
                4, "sigma"},
        BadSpec{"stage names a parameter that is not free",
                "format: pneumaid-fit/1\nparameters: {pipeline.delta: {min: 1, max: 9}}\n"
                "stages:\n  - [valve.increasing.q_max]\n",
                4, "not under parameters"},
        BadSpec{"a parameter listed twice in one stage",
                "format: pneumaid-fit/1\nparameters: {pipeline.delta: {min: 1, max: 9}}\n"
                "stages:\n  - [pipeline.delta, pipeline.delta]\n",
                4, "'pipeline.delta' listed twice in one stage"},
        BadSpec{"a last stage that leaves a free parameter out",
                "format: pneumaid-fit/1\nparameters:\n  pipeline.delta: {min: 1, max: 9}\n"
                "  valve.increasing.q_max: {min: 1e-4, max: 1e-2}\n"
                "stages:\n  - all\n  - [pipeline.delta]\n",
                7, "the last stage must fit every free parameter ('valve.increasing.q_max'"},
        BadSpec{"friction replay as the last stage",
                "format: pneumaid-fit/1\nparameters: {pipeline.delta: {min: 1, max: 9}}\n"
                "stages:\n  - {friction_replay: true}\n",
                4, "last stage"},
        BadSpec{"a stage mapping without parameters",
                "format: pneumaid-fit/1\nparameters: {pipeline.delta: {min: 1, max: 9}}\n"
                "stages:\n  - {windows: true}\n  - all\n",
                4, "expected parameters: [paths] or parameters: all"},
        BadSpec{"friction replay with parameters",
                "format: pneumaid-fit/1\nparameters: {pipeline.delta: {min: 1, max: 9}}\n"
                "stages:\n  - {friction_replay: true, parameters: all}\n  - all\n",
                4, "stands alone"},
        BadSpec{"initial pressures neither fit nor logged",
                "format: pneumaid-fit/1\nparameters: {pipeline.delta: {min: 1, max: 9}}\n"
                "initial_pressures: guess\n",
                3, "fit or logged"},
        BadSpec{"fractional multistart",
                "format: pneumaid-fit/1\nparameters: {pipeline.delta: {min: 1, max: 9}}\n"
                "multistart: 1.5\n",
                3, "whole number"},
        BadSpec{"syntax", "format: pneumaid-fit/1\nparameters: {pipeline.delta: [\n", 3,
                "YAML syntax"}));

// FitSpec::IsValid: a spec built in code is checked as strictly as one read
// from YAML, and the message names the field.
TEST(FitSpecTest, IsValidNamesTheBadFieldOfASpecBuiltInCode) {
  const FitSpec good = LoadFitSpec(std::string(PNEUMAID_SOURCE_DIR) + "/configs/fit-default.yaml");
  std::string error;
  EXPECT_TRUE(good.IsValid(&error)) << error;
  struct Case {
    const char* what;
    void (*spoil)(FitSpec*);
    const char* expected;
  };
  const Case cases[] = {
      {"no parameter", [](FitSpec* s) { s->parameters.clear(); }, "parameters: expected"},
      {"unknown path", [](FitSpec* s) { s->parameters[0].path = "pipeline.gamma"; },
       "unknown parameter 'pipeline.gamma'"},
      {"freed twice", [](FitSpec* s) { s->parameters.push_back(s->parameters[0]); },
       "parameters.pipeline.delta: freed twice"},
      {"min above max", [](FitSpec* s) { s->parameters[0].lower = 600; },
       "parameters.pipeline.delta: expected min < max"},
      {"log scale through zero",
       [](FitSpec* s) { s->parameters[2].scale = ParameterScale::kLog; },  // Fs from 0
       "parameters.friction.positive.Fs: a log scale needs min > 0"},
      {"outside the physical range", [](FitSpec* s) { s->parameters[2].lower = -1; },
       "parameters.friction.positive.Fs: bounds must each be a finite number"},
      {"an effect's parameter the catalog does not have",
       [](FitSpec* s) { s->parameters[0].path = "effects.valve_lag.delay"; },
       "unknown parameter 'effects.valve_lag.delay'"},
      {"an effect's bound outside what the model accepts",
       [](FitSpec* s) {
         s->parameters[0] = {"effects.valve_lag.tau", 0, 0.1};
       },
       "parameters.effects.valve_lag.tau: bounds must each be a finite number"},
      {"too many",
       [](FitSpec* s) {
         for (const char* p : {"friction.positive.Fs", "valve.decreasing.q_max",
                               "valve.increasing.a", "valve.increasing.b", "valve.increasing.c"})
           s->parameters.push_back({p, 0.1, 1, ParameterScale::kLinear});
       },
       "parameters: at most"},
      {"unknown channel", [](FitSpec* s) { s->channels["v"] = ChannelWeight{}; },
       "unknown channel 'v'"},
      {"zero weight", [](FitSpec* s) { s->channels["x"].weight = 0; }, "channels.x: expected"},
      {"nothing to fit", [](FitSpec* s) { s->fit.clear(); }, "experiments.fit"},
      {"stage names a fixed parameter", [](FitSpec* s) { s->stages[0].parameters = {"gas.T"}; },
       "stages: 'gas.T' is not under parameters"},
      {"stage names a parameter twice",
       [](FitSpec* s) {
         s->stages[0].parameters = {"pipeline.delta", "pipeline.delta"};
       },
       "stages: 'pipeline.delta' listed twice in one stage"},
      {"last stage leaves one out",
       [](FitSpec* s) { s->stages.back().parameters = {"pipeline.delta"}; },
       "the last stage must fit every free parameter ("},
      {"replay last",
       [](FitSpec* s) {
         s->stages.back() = FitStage{{}, false, true};
       },
       "the last stage must fit"},
      {"no iterations", [](FitSpec* s) { s->max_iterations = 0; }, "max_iterations"},
  };
  for (const Case& c : cases) {
    FitSpec spec = good;
    c.spoil(&spec);
    EXPECT_FALSE(spec.IsValid(&error)) << c.what;
    EXPECT_NE(error.find(c.expected), std::string::npos) << c.what << ": " << error;
  }
}

}  // namespace
}  // namespace pneumaid
