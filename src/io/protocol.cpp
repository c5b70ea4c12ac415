#include "pneumaid/io/protocol.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdlib>
#include <set>

#include "pneumaid/io/files.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/units.h"
#include "yaml_reader.h"

namespace pneumaid {
namespace {

class ProtocolReader : internal::YamlReader {
 public:
  explicit ProtocolReader(std::string source) : YamlReader(std::move(source)) {}

  Protocol Read(const std::string& text) {
    return Guarded([&] { return ReadDocument(text); });
  }

 private:
  Protocol ReadDocument(const std::string& text) {
    const YAML::Node root =
        LoadMapping(text, "expected a mapping starting with format: pneumaid-protocol/1");
    Keys(root, "",
         {"format", "sample_rate", "dropped_samples", "clock_jitter", "position_origin", "units",
          "sensors", "valve", "pipeline", "stroke", "validation", "mismatch"});
    if (!root["format"] || Text(root["format"]) != kProtocolFormat) {
      Fail(root, std::string("expected format: ") + kProtocolFormat);
    }
    Protocol p;
    if (root["sample_rate"]) p.sample_rate_Hz = Positive(root["sample_rate"], "sample_rate");
    if (const YAML::Node dropped = root["dropped_samples"]) {
      p.dropped_samples = Number(dropped, "dropped_samples");
      if (!(p.dropped_samples >= 0 && p.dropped_samples < 0.5))
        Fail(dropped, "expected dropped_samples in [0, 0.5)");
    }
    if (const YAML::Node jitter = root["clock_jitter"]) {
      p.clock_jitter = Number(jitter, "clock_jitter");
      if (!(p.clock_jitter >= 0 && p.clock_jitter < 0.5))
        Fail(jitter, "expected clock_jitter in [0, 0.5)");
    }
    if (const YAML::Node origin = root["position_origin"]) {
      const std::string text = Text(origin);
      if (text != "mid" && text != "retracted") Fail(origin, "expected mid | retracted");
      p.position_origin = text == "mid" ? PositionOrigin::kMid : PositionOrigin::kRetracted;
    }
    ReadUnits(root["units"], &p);
    ReadSensors(root["sensors"], &p);
    if (const YAML::Node valve = root["valve"]) {
      Keys(valve, "valve.", {"step", "hold", "ramp", "levels"});
      p.valve = true;
      if (valve["step"]) p.valve_step_V = Positive(valve["step"], "valve.step");
      if (valve["hold"]) p.valve_hold_s = Positive(valve["hold"], "valve.hold");
      if (valve["ramp"]) p.valve_ramp_s = Positive(valve["ramp"], "valve.ramp");
      if (const YAML::Node levels = valve["levels"]) {
        if (valve["ramp"] || valve["step"]) {
          Fail(levels, "valve.levels: a list of levels is the test; step and ramp make another");
        }
        if (!levels.IsSequence() || levels.size() == 0)
          Fail(levels, "valve.levels: expected a non-empty list of commands in [0, 1] V");
        for (const auto& level : levels) {
          p.valve_levels_V.push_back(NonNegative(level, "valve.levels"));
          if (p.valve_levels_V.back() > 1)
            Fail(level, "valve.levels: expected commands in [0, 1] V");
        }
      }
    }
    if (const YAML::Node pipe = root["pipeline"]) {
      Keys(pipe, "pipeline.", {"tube_lengths", "command", "step_time", "duration", "schedule"});
      p.tube_lengths_m = List(pipe["tube_lengths"], "pipeline.tube_lengths");
      if (pipe["command"]) p.pipeline_command_V = Positive(pipe["command"], "pipeline.command");
      if (pipe["step_time"])
        p.pipeline_step_time_s = Positive(pipe["step_time"], "pipeline.step_time");
      if (pipe["duration"]) p.pipeline_duration_s = Positive(pipe["duration"], "pipeline.duration");
      if (pipe["schedule"]) p.pipeline_schedule = Schedule(pipe["schedule"], "pipeline.schedule");
      if (p.pipeline_command_V > 1) Fail(pipe["command"], "pipeline.command: expected <= 1 V");
      for (std::size_t k = 0; k < p.pipeline_schedule.size(); ++k) {
        // A knot the test never reaches, or a command the valve cannot take.
        const auto [time, level] = p.pipeline_schedule[k];
        if (!(time < p.pipeline_duration_s) || !(std::fabs(level) <= 1))
          Fail(pipe["schedule"][k],
               "pipeline.schedule: expected each knot before "
               "pipeline.duration and a level in [-1, 1] V");
      }
    }
    if (const YAML::Node stroke = root["stroke"]) {
      Keys(stroke, "stroke.", {"levels", "cycles", "margin", "max_leg", "dwell"});
      p.stroke_levels_V = List(stroke["levels"], "stroke.levels");
      for (const double level : p.stroke_levels_V) {
        if (level > 1) Fail(stroke["levels"], "stroke.levels: expected commands in (0, 1] V");
      }
      if (stroke["margin"]) p.stroke_margin_m = NonNegative(stroke["margin"], "stroke.margin");
      if (stroke["dwell"]) p.stroke_dwell_s = NonNegative(stroke["dwell"], "stroke.dwell");
      if (stroke["max_leg"]) p.stroke_max_leg_s = Positive(stroke["max_leg"], "stroke.max_leg");
      p.stroke_cycles = Count(stroke["cycles"], "stroke.cycles", 1, 100, p.stroke_cycles);
    }
    if (const YAML::Node validation = root["validation"]) {
      Keys(validation, "validation.", {"paper_step", "rich_profile"});
      p.paper_step = validation["paper_step"] && Flag(validation["paper_step"]);
      p.rich_profile = validation["rich_profile"] && Flag(validation["rich_profile"]);
    }
    if (const YAML::Node mismatch = root["mismatch"]) {
      Keys(mismatch, "mismatch.", {"friction", "stick_velocity", "relative_tolerance"});
      if (const YAML::Node friction = mismatch["friction"]) {
        const std::string text = Text(friction);
        if (text != "events" && text != "regularized")
          Fail(friction, "mismatch.friction: expected events | regularized");
        p.mismatch.regularized_friction = text == "regularized";
      }
      if (mismatch["stick_velocity"]) {
        p.mismatch.stick_velocity_m_per_s =
            Positive(mismatch["stick_velocity"], "mismatch.stick_velocity");
      }
      if (mismatch["relative_tolerance"]) {
        p.mismatch.relative_tolerance =
            Positive(mismatch["relative_tolerance"], "mismatch.relative_tolerance");
      }
    }
    return p;
  }

  double NonNegative(const YAML::Node& node, const std::string& path) const {
    const double value = Number(node, path);
    if (!(value >= 0)) Fail(node, path + ": expected a number >= 0");
    return value;
  }

  // [[time, level], ...] with times increasing.
  std::vector<std::pair<double, double>> Schedule(const YAML::Node& node,
                                                  const std::string& path) const {
    const char* expected = ": expected a list of [time, level] pairs with increasing times >= 0";
    if (!node.IsSequence() || node.size() == 0) Fail(node, path + expected);
    std::vector<std::pair<double, double>> knots;
    for (const YAML::Node& knot : node) {
      if (!knot.IsSequence() || knot.size() != 2) Fail(knot, path + expected);
      const double time = Number(knot[0], path);
      if (!(time >= 0) || (!knots.empty() && !(time > knots.back().first)))
        Fail(knot, path + expected);
      knots.emplace_back(time, Number(knot[1], path));
    }
    return knots;
  }

  void ReadUnits(const YAML::Node& units, Protocol* p) const {
    if (!units) return;
    Keys(units, "units.", {"length", "pressure", "flow"});
    const auto pick = [&](const char* key, std::vector<Quantity> quantities, std::string* out) {
      if (!units[key]) return;
      const std::string symbol = Text(units[key]);
      const UnitInfo* unit = FindUnit(symbol);
      bool ok = false;
      for (Quantity q : quantities) ok = ok || (unit && unit->quantity == q);
      if (!ok)
        Fail(units[key],
             std::string("units.") + key + ": expected one of " + AcceptedUnits(quantities));
      *out = symbol;
    };
    pick("length", {Quantity::kLength}, &p->length_unit);
    pick("pressure", {Quantity::kPressure}, &p->pressure_unit);
    pick("flow", {Quantity::kVolumetricFlow, Quantity::kMassFlow}, &p->flow_unit);
  }

  void ReadSensors(const YAML::Node& sensors, Protocol* p) const {
    if (!sensors) return;
    Keys(sensors, "sensors.",
         {"t", "u", "x", "p_up", "p_down", "p_in", "p_out", "p1", "p2", "q", "q_in", "q_out", "q1",
          "q2"});
    for (const auto& entry : sensors) {
      const std::string name = Key(entry.first);
      const std::string path = "sensors." + name + ".";
      Keys(entry.second, path, {"sigma", "tau", "quantization", "declared"});
      SensorModel model;
      if (entry.second["sigma"]) model.sigma = Number(entry.second["sigma"], path + "sigma");
      if (entry.second["tau"]) model.tau_s = Number(entry.second["tau"], path + "tau");
      if (entry.second["quantization"]) {
        model.quantization = Number(entry.second["quantization"], path + "quantization");
      }
      if (entry.second["declared"]) model.declared = Flag(entry.second["declared"]);
      if (model.sigma < 0 || model.tau_s < 0 || model.quantization < 0) {
        Fail(entry.second, path + ": expected sigma, tau, quantization >= 0");
      }
      p->sensors[name] = model;
    }
  }
};

}  // namespace

Protocol ParseProtocol(const std::string& text, const std::string& source) {
  return ProtocolReader(source).Read(text);
}

Protocol LoadProtocol(const std::string& path) {
  return ParseProtocol(ReadTextFile(path, "protocol file"), path);
}

}  // namespace pneumaid
