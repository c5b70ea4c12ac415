#include "pneumaid/io/log_notes.h"

#include <gtest/gtest.h>

#include <string>
#include <tuple>
#include <vector>

namespace pneumaid {
namespace {

Experiment Log(const std::string& id, ExperimentKind kind, std::vector<double> t) {
  Experiment e;
  e.entry.id = id;
  e.entry.kind = kind;
  e.columns["t"] = std::move(t);
  return e;
}

std::vector<double> Clock(std::size_t samples, double dt_s) {
  std::vector<double> t(samples);
  for (std::size_t i = 0; i < samples; ++i) t[i] = i * dt_s;
  return t;
}

std::string Joined(const std::vector<std::string>& notes) {
  std::string out;
  for (const auto& note : notes) out += note + "\n";
  return out;
}

// A dropped row (twice the interval) or two is common and harmless; rows lost
// for longer are a gap, and the longest is located.
TEST(LogNotesTest, NamesSamplingGapsAndTheLongestNotASingleDroppedRow) {
  std::vector<double> t = Clock(1000, 1e-3);
  t.erase(t.begin() + 100);  // one row dropped: no note
  EXPECT_TRUE(LogNotes(Log("stroke-1", ExperimentKind::kStroke, t)).empty());
  t.erase(t.begin() + 500, t.begin() + 521);  // 21 rows lost after t = 0.500 s
  t.erase(t.begin() + 800, t.begin() + 805);  // 5 more further on
  // Shown in the log's own time (its first sample at 1000 s here).
  Experiment e = Log("stroke-1", ExperimentKind::kStroke, t);
  e.time_origin_s = 1000;
  const std::string notes = Joined(LogNotes(e));
  EXPECT_NE(notes.find("2 gaps in the sampling"), std::string::npos) << notes;
  EXPECT_NE(notes.find("the longest 22 ms after t = 1000.5 s, about 21 samples missing"),
            std::string::npos)
      << notes;
}

// The one gap rule: an interval over 3.5 times the median (4 ms at 1 ms is,
// 3 ms is not), each gap's index in order, and the median it was measured on.
TEST(LogNotesTest, SamplingGapsAreIntervalsOverThreeAndAHalfMedians) {
  std::vector<double> t = Clock(100, 1e-3);
  t.erase(t.begin() + 10, t.begin() + 12);  // 3 ms from t[9] to t[10]
  t.erase(t.begin() + 50, t.begin() + 53);  // 4 ms from t[49] to t[50]
  t.erase(t.begin() + 80, t.begin() + 90);  // 11 ms from t[79] to t[80]
  double median_s = 0;
  EXPECT_EQ(SamplingGaps(t, &median_s), (std::vector<std::size_t>{49, 79}));
  EXPECT_NEAR(median_s, 1e-3, 1e-12);
  EXPECT_TRUE(SamplingGaps({0.0, 1.0}).empty());
  EXPECT_TRUE(SamplingGaps({0.0, 0.0, 0.0, 5.0}).empty());  // a median of 0: no rule
}

TEST(LogNotesTest, NamesALastRowWithoutALineEnd) {
  Experiment e = Log("valve-1", ExperimentKind::kValve, Clock(100, 1e-3));
  EXPECT_TRUE(LogNotes(e).empty());
  e.unterminated_last_row = true;
  const std::string notes = Joined(LogNotes(e));
  EXPECT_NE(notes.find("the last row has no line end"), std::string::npos) << notes;
}

// A supply written in a gauge unit on a rig whose valve test logs the absolute
// supply upstream (5 bar_g = 6.01 bar abs against 5 bar abs logged): named,
// with the size of the contradiction. A valve log at the supply, or chambers
// below it, say nothing.
TEST(LogNotesTest, NamesASupplyPressureTheLogsContradict) {
  Unit unit;
  unit.manifest.rig.supply_pressure_Pa = 5e5;
  unit.experiments.push_back(Log("valve-1", ExperimentKind::kValve, Clock(100, 1e-3)));
  unit.experiments[0].columns["p_up"] = std::vector<double>(100, 4.98e5);
  unit.experiments.push_back(Log("stroke-1", ExperimentKind::kStroke, Clock(100, 1e-3)));
  unit.experiments[1].columns["p1"] = std::vector<double>(100, 5.0e5);
  unit.experiments[1].columns["p2"] = std::vector<double>(100, 1.0e5);
  unit.experiments[1].columns["p2"][50] = 7.0e5;  // a moment's compression
  EXPECT_TRUE(ManifestNotes(unit).empty()) << Joined(ManifestNotes(unit));

  unit.manifest.rig.supply_pressure_Pa = 6.01325e5;
  std::string notes = Joined(ManifestNotes(unit));
  EXPECT_NE(notes.find("valve log 'valve-1': p_up's median 4.98 bar abs is 17 % below the rig's "
                       "supply_pressure 6.013 bar abs (a gauge unit"),
            std::string::npos)
      << notes;
  EXPECT_EQ(notes.find("stroke-1"), std::string::npos) << notes;

  unit.manifest.rig.supply_pressure_Pa = 4e5;
  notes = Joined(ManifestNotes(unit));
  EXPECT_NE(notes.find("25 % above the rig's supply_pressure 4 bar abs"), std::string::npos)
      << notes;
  EXPECT_NE(notes.find("log 'stroke-1': the higher chamber pressure exceeds 5 bar abs for 1 % of "
                       "the log, 25 % above"),
            std::string::npos)
      << notes;
}

// The same log listed under two ids (a stroke test listed again as a
// validation run: its held-out figures would be the fit's own): named once,
// with both ids and kinds. Logs of other bytes say nothing.
TEST(LogNotesTest, NamesALogListedTwice) {
  Unit unit;
  unit.manifest.rig.supply_pressure_Pa = 5e5;
  for (const auto& [id, kind, hash] :
       {std::make_tuple("stroke-1", ExperimentKind::kStroke, "aa"),
        std::make_tuple("stroke-2", ExperimentKind::kStroke, "bb"),
        std::make_tuple("step", ExperimentKind::kValidation, "aa")}) {
    unit.experiments.push_back(Log(id, kind, Clock(100, 1e-3)));
    unit.experiments.back().sha256 = hash;
  }
  const std::string notes = Joined(ManifestNotes(unit));
  EXPECT_NE(notes.find("logs 'stroke-1' (stroke) and 'step' (validation) are the same bytes"),
            std::string::npos)
      << notes;
  EXPECT_EQ(notes.find("stroke-2"), std::string::npos) << notes;
  unit.experiments.back().sha256 = "cc";
  EXPECT_TRUE(ManifestNotes(unit).empty()) << Joined(ManifestNotes(unit));
}

}  // namespace
}  // namespace pneumaid
