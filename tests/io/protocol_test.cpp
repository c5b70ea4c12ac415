// The synthetic rig's protocol format: the shipped protocols parse, and a bad
// stroke.cycles is one message naming the line.
#include "pneumaid/io/protocol.h"

#include <gtest/gtest.h>

#include "pneumaid/io/input_error.h"

namespace pneumaid {
namespace {

TEST(ProtocolTest, TheFullProtocolRunsThreeStrokeCyclesPerLevel) {
  const Protocol p = LoadProtocol(std::string(PNEUMAID_SOURCE_DIR) + "/configs/protocol-full.yaml");
  EXPECT_EQ(p.stroke_cycles, 3);
  EXPECT_EQ(p.stroke_levels_V.size(), 5u);
  const Protocol fleet =
      LoadProtocol(std::string(PNEUMAID_SOURCE_DIR) + "/configs/protocol-fleet.yaml");
  EXPECT_EQ(fleet.stroke_cycles, 1);  // the default
}

TEST(ProtocolTest, StrokeCyclesMustBeAWholeNumberFromOneToAHundred) {
  for (const char* cycles : {"0.5", "0", "101", "-2"}) {
    const std::string text = std::string("format: pneumaid-protocol/1\n") +
                             "stroke: {levels: [0.5],\n  cycles: " + cycles + "}\n";
    try {
      ParseProtocol(text, "p.yaml");
      ADD_FAILURE() << "cycles " << cycles << " accepted";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), "p.yaml");
      EXPECT_EQ(e.line(), 3) << cycles;
      EXPECT_NE(e.message().find("cycles"), std::string::npos) << e.message();
    }
  }
  EXPECT_EQ(ParseProtocol("format: pneumaid-protocol/1\nstroke: {levels: [0.5], cycles: 4}\n", "p")
                .stroke_cycles,
            4);
}

TEST(ProtocolTest, ATubeScheduleAStrokeDwellAndAMismatchAreRead) {
  const Protocol p = ParseProtocol(
      "format: pneumaid-protocol/1\n"
      "pipeline: {tube_lengths: [0.38], schedule: [[0.1, 1.0], [1.2, 0]], duration: 2}\n"
      "stroke: {levels: [0.3], margin: 0, dwell: 0.2}\n"
      "mismatch: {friction: regularized, stick_velocity: 2.0e-4, relative_tolerance: 1.0e-9}\n",
      "p");
  ASSERT_EQ(p.pipeline_schedule.size(), 2u);
  EXPECT_EQ(p.pipeline_schedule[1].first, 1.2);
  EXPECT_EQ(p.pipeline_schedule[1].second, 0.0);
  EXPECT_EQ(p.stroke_margin_m, 0.0);
  EXPECT_EQ(p.stroke_dwell_s, 0.2);
  EXPECT_TRUE(p.mismatch.regularized_friction);
  EXPECT_EQ(p.mismatch.stick_velocity_m_per_s, 2.0e-4);
  EXPECT_EQ(p.mismatch.relative_tolerance, 1.0e-9);
}

TEST(ProtocolTest, AValveRampALossyLoggerAndAnIrregularClockAreRead) {
  const Protocol p = ParseProtocol(
      "format: pneumaid-protocol/1\n"
      "dropped_samples: 0.01\n"
      "clock_jitter: 0.3\n"
      "valve: {ramp: 6}\n",
      "p");
  EXPECT_TRUE(p.valve);
  EXPECT_EQ(p.valve_ramp_s, 6.0);
  EXPECT_EQ(p.dropped_samples, 0.01);
  EXPECT_EQ(p.clock_jitter, 0.3);
  EXPECT_EQ(ParseProtocol("format: pneumaid-protocol/1\nvalve: {step: 0.1}\n", "p").valve_ramp_s,
            0.0);  // a staircase by default
  // Levels in any order, each held `hold`.
  const Protocol levels = ParseProtocol(
      "format: pneumaid-protocol/1\nvalve: {levels: [0.3, 0, 1, 0.05], hold: 0.2}\n", "p");
  EXPECT_EQ(levels.valve_levels_V, (std::vector<double>{0.3, 0, 1, 0.05}));
  EXPECT_EQ(levels.valve_hold_s, 0.2);
}

TEST(ProtocolTest, ABadScheduleOrMismatchNamesItsLine) {
  for (const char* bad :
       {"pipeline: {tube_lengths: [0.38],\n  schedule: [[0.5, 1], [0.2, 0]]}\n",
        "pipeline: {tube_lengths: [0.38],\n  schedule: [[0.5]]}\n",
        "mismatch:\n  friction: smooth\n", "mismatch: {relative_tolerance: 0,\n  x: 1}\n",
        "\ndropped_samples: 0.5\n", "\nclock_jitter: 0.5\n", "valve:\n  ramp: -1\n",
        "valve: {hold: 0.2,\n  levels: [0.5, 1.2]}\n", "valve: {ramp: 6,\n  levels: [0.5]}\n",
        "valve:\n  levels: []\n",
        // Protocols the rig cannot run: a command above 1 V, a knot after the test.
        "stroke:\n  levels: [0.5, 1.2]\n", "pipeline: {tube_lengths: [0.38],\n  command: 1.5}\n",
        "pipeline: {tube_lengths: [0.38], duration: 2,\n  schedule: [[0.1, 1], [3.0, 0]]}\n",
        "pipeline: {tube_lengths: [0.38],\n  schedule: [[0.1, 2]]}\n"}) {
    try {
      ParseProtocol(std::string("format: pneumaid-protocol/1\n") + bad, "p.yaml");
      ADD_FAILURE() << bad << " accepted";
    } catch (const InputError& e) {
      EXPECT_GE(e.line(), 2) << bad;
    }
  }
}

TEST(ProtocolTest, NumbersAreReadTheSameWhateverTheHostsLocale) {
  // std::from_chars: a host program's setlocale cannot change what is read.
  const Protocol p = ParseProtocol("format: pneumaid-protocol/1\nsample_rate: +2.5e3\n", "p");
  EXPECT_EQ(p.sample_rate_Hz, 2500.0);
  EXPECT_THROW(ParseProtocol("format: pneumaid-protocol/1\nsample_rate: 2,5\n", "p"), InputError);
  EXPECT_THROW(ParseProtocol("format: pneumaid-protocol/1\nsample_rate: +-2\n", "p"), InputError);
}

}  // namespace
}  // namespace pneumaid
