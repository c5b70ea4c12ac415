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

}  // namespace
}  // namespace pneumaid
