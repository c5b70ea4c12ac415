// A parameter set's provenance (pneumaid/io/provenance.h): read whatever a
// set carries (a mapping, free text, nothing), add an entry that replaces an
// earlier one of its name, and stay valid YAML whatever the values hold.
#include "pneumaid/io/provenance.h"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <map>
#include <string>
#include <vector>

#include "../../src/io/provenance_map.h"

namespace pneumaid {
namespace {

TEST(ProvenanceTest, ReadsAnEntryAndItsList) {
  const std::string provenance =
      "{identify: {unit: u1}, refine: {status: converged, at_bound: [friction.positive.Fd, "
      "friction.negative.b]}}";
  EXPECT_TRUE(HasProvenanceEntry(provenance, "refine"));
  EXPECT_TRUE(HasProvenanceEntry(provenance, "identify"));
  EXPECT_FALSE(HasProvenanceEntry(provenance, "diagnose"));
  EXPECT_EQ(ProvenanceList(provenance, "refine", "at_bound"),
            (std::vector<std::string>{"friction.positive.Fd", "friction.negative.b"}));
  EXPECT_TRUE(ProvenanceList(provenance, "refine", "missing").empty());
  EXPECT_TRUE(ProvenanceList(provenance, "identify", "unit").empty());  // not a list
}

TEST(ProvenanceTest, ReadsAMappingOfAnEntryOrOfTheTopLevel) {
  const std::string provenance =
      "{tool: pneumaid, held: {friction.positive.vs: \"no slide below 5 mm/s\"}, refine: "
      "{held: {effects.stick_creep.v: \"held at a point: 1e-4\", bad: [1, 2]}, at_bound: [x]}}";
  using Strings = std::map<std::string, std::string>;
  EXPECT_EQ(ProvenanceStrings(provenance, "refine", "held"),
            (Strings{{"effects.stick_creep.v", "held at a point: 1e-4"}}));  // not a string: left
  EXPECT_EQ(ProvenanceStrings(provenance, "", "held"),
            (Strings{{"friction.positive.vs", "no slide below 5 mm/s"}}));
  EXPECT_TRUE(ProvenanceStrings(provenance, "refine", "at_bound").empty());  // a list
  EXPECT_TRUE(ProvenanceStrings(provenance, "identify", "held").empty());
  EXPECT_TRUE(ProvenanceStrings("free text", "", "held").empty());
}

TEST(ProvenanceTest, TextThatIsNotAMappingIsOneEntryGiven) {
  for (const std::string text : {"measured on rig 3, see the log book", "[unbalanced", ""}) {
    EXPECT_FALSE(HasProvenanceEntry(text, "refine")) << text;
    EXPECT_TRUE(ProvenanceList(text, "refine", "at_bound").empty()) << text;
    const YAML::Node map = ProvenanceMap(text);
    ASSERT_TRUE(map.IsMap()) << text;
    EXPECT_EQ(map["given"].IsDefined(), !text.empty()) << text;
  }
  EXPECT_EQ(ProvenanceMap("[unbalanced")["given"].as<std::string>(), "[unbalanced");
}

TEST(ProvenanceTest, AnEntryReplacesAnEarlierOneAndStaysValidYaml) {
  YAML::Node first(YAML::NodeType::Map);
  first["spec"] = "a.yaml";
  const std::string once = WithProvenanceEntry("{identify: {unit: u1}}", "refine", first);
  YAML::Node second(YAML::NodeType::Map);
  second["spec"] = "C:\\specs\\it's \"quoted\": {b}.yaml";
  const std::string twice = WithProvenanceEntry(once, "refine", second);
  const YAML::Node root = YAML::Load(twice);  // throws if not valid YAML
  ASSERT_TRUE(root.IsMap());
  EXPECT_EQ(root.size(), 2u);
  EXPECT_EQ(root["identify"]["unit"].as<std::string>(), "u1");
  EXPECT_EQ(root["refine"]["spec"].as<std::string>(), second["spec"].as<std::string>());
  EXPECT_TRUE(HasProvenanceEntry(twice, "refine"));
  // Free text is kept beside the new entry.
  const YAML::Node kept = YAML::Load(WithProvenanceEntry("from the vendor", "refine", first));
  EXPECT_EQ(kept["given"].as<std::string>(), "from the vendor");
  EXPECT_EQ(kept["refine"]["spec"].as<std::string>(), "a.yaml");
}

}  // namespace
}  // namespace pneumaid
