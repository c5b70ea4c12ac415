#include <algorithm>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "commands.h"
#include "pneumaid/io/channel_noise.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/log_notes.h"
#include "pneumaid/io/rig_data.h"
#include "pneumaid/io/rig_writer.h"
#include "pneumaid/validate/lag_start.h"
#include "pneumaid/validate/logged_run.h"

namespace pneumaid::cli {
namespace {

// "x [mm] 0.012 .. 49.98" in the unit the log was written in.
std::string ChannelRange(const Experiment& experiment, const std::string& name,
                         const RigConstants& rig) {
  const auto& values = experiment.column(name);
  const auto [low, high] = std::minmax_element(values.begin(), values.end());
  std::string unit = experiment.units_as_written.at(name);
  double shift = 0;
  if (name == "x" && rig.position_origin == PositionOrigin::kRetracted) shift = 0.5 * rig.stroke_m;
  const auto shown = [&](double si) {
    if (unit.empty()) return si + shift;
    return FromSI(unit, si + shift, rig.atmospheric_pressure_Pa, rig.air_density_kg_per_m3);
  };
  char text[128];
  std::snprintf(text, sizeof(text), "%s [%s] %.6g .. %.6g", name.c_str(),
                unit.empty() ? "SI" : unit.c_str(), shown(*low), shown(*high));
  return text;
}

void PrintUnit(const Unit& unit) {
  const Manifest& m = unit.manifest;
  std::cout << "unit " << m.unit << " (" << unit.directory << "): " << unit.experiments.size()
            << " experiments, " << ToString(m.rig.orientation) << ", supply "
            << m.rig.supply_pressure_Pa / 1e5 << " bar abs, stroke " << m.rig.stroke_m * 1e3
            << " mm, origin " << ToString(m.rig.position_origin) << "\n";
  if (!m.defaults_used.empty()) {
    std::cout << "  defaults used:";
    for (const auto& path : m.defaults_used) std::cout << " " << path;
    std::cout << "\n";
  }
  // What the fits will weigh each logged channel by, where the manifest does
  // not say it or the logs contradict it.
  const std::string noise =
      ChannelNoiseNote(unit, {"x", "p1", "p2", "p_up", "p_down", "q", "q_in", "q_out", "q1", "q2"});
  if (!noise.empty()) std::cout << "  " << noise << "\n";
  const PositionZero zero = ReadPositionZero(unit);
  if (zero.offset_m != 0) std::cout << "  " << zero.note << "\n";
  for (const auto& note : ManifestNotes(unit)) std::cout << "  note: " << note << "\n";
  for (const Experiment& e : unit.experiments) {
    const auto& t = e.column("t");
    const double duration = t.back() - t.front();
    const double rate = t.size() > 1 ? (t.size() - 1) / duration : 0.0;
    std::cout << "  " << e.entry.id << ": " << ToString(e.entry.kind) << ", " << e.samples()
              << " samples, " << duration << " s at " << rate << " Hz";
    if (e.entry.tube_length_m) std::cout << ", tube " << *e.entry.tube_length_m << " m";
    std::cout << "\n   ";
    for (const auto& [name, values] : e.columns) {
      if (name != "t") std::cout << " " << ChannelRange(e, name, m.rig) << ";";
    }
    std::cout << "\n";
    if (!e.ignored_columns.empty()) {
      std::cout << "    ignored columns:";
      for (const auto& name : e.ignored_columns) std::cout << " " << name;
      std::cout << "\n";
    }
    for (const auto& note : LogNotes(e)) std::cout << "    note: " << note << "\n";
    const Trajectory run = e.AsTrajectory();
    if (!run.x_m.empty() && !run.p1_Pa.empty() && !run.p2_Pa.empty() && StartsUnsettled(run)) {
      std::cout << "    note: the log starts unsettled (the rod moving or a chamber filling "
                   "before its command changes: a log cut mid-run); validation and refinement "
                   "read its valves' lag states off its first 100 ms\n";
    }
  }
}

}  // namespace

CommandRunner AddCheckCommand(CLI::App* app) {
  auto dirs = std::make_shared<std::vector<std::string>>();
  app->add_option("units", *dirs, "unit directories")->required();
  return [dirs]() {
    int status = kSuccess;
    for (const auto& dir : *dirs) {
      try {
        PrintUnit(ReadUnit(dir));
      } catch (const InputError& error) {
        std::cerr << "error: " << error.what() << "\n";
        status = kBadInput;
      }
    }
    return status;
  };
}

}  // namespace pneumaid::cli
