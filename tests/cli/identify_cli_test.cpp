// `pneumaid identify` then `validate` on the bundled unit; bad input writes nothing.
#include <gtest/gtest.h>

#include <filesystem>

#include "cli_test_util.h"

namespace pneumaid {
namespace {

using IdentifyCliTest = testing::CliTest;

TEST_F(IdentifyCliTest, IdentifiedSetValidates) {
  const std::string out = (dir_ / "identified.yaml").string();
  ASSERT_EQ(Run("identify " + testing::Source("datasets/paper-rig") + " --only valve --out " + out),
            0)
      << Stderr();
  EXPECT_NE(Stdout().find("From the prior"), std::string::npos);
  EXPECT_NE(Read(out).find("sha256"), std::string::npos);
  EXPECT_EQ(Run("validate --params " + out + " " + testing::Source("datasets/paper-rig")), 0)
      << Stdout() << Stderr();
}

TEST_F(IdentifyCliTest, BadInputExitsTwoAndWritesNothing) {
  const std::string out = (dir_ / "identified.yaml").string();
  EXPECT_EQ(Run("identify " + testing::Source("datasets/fleet/PVQ13-0014") + " --out " + out), 2);
  EXPECT_EQ(
      Run("identify " + testing::Source("datasets/paper-rig") + " --only valves --out " + out), 2);
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace pneumaid
