#include "pneumaid/synth/synthetic_rig.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <utility>

#include "../util/splitmix64.h"
#include "pneumaid/eval/lag.h"
#include "pneumaid/io/input_error.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/model/actuator.h"
#include "pneumaid/model/gas.h"
#include "pneumaid/model/parameter_table.h"
#include "pneumaid/sim/simulate.h"

namespace pneumaid {
namespace {

constexpr double kPi = 3.14159265358979323846;
// The rig-data format's default air density: standard conditions.
const double kAirDensity_kg_per_m3 = RigConstants{}.air_density_kg_per_m3;
constexpr double kHysteresisThreshold_V = 0.01;
// Offset of the dropped-rows streams from the experiments' noise streams.
constexpr std::uint64_t kDroppedRowsStream = 1000003;
// And of the irregular clocks' streams (Protocol::clock_jitter).
constexpr std::uint64_t kClockStream = 2000003;

// One random stream per experiment, derived from the seed and the experiment
// index, so adding an experiment does not change the noise of the others.
std::uint64_t StreamSeed(std::uint64_t seed, std::uint64_t index) {
  return internal::SplitMix64Mix(seed + internal::kSplitMix64Increment * (index + 1));
}

double EffectValue(const Parameters& p, const char* name, const char* key) {
  const auto effect = p.effects.find(name);
  return effect == p.effects.end() ? 0.0 : effect->second.at(key);
}

// The times at which one log's rows are taken: the protocol's rate, or an
// irregular clock (Protocol::clock_jitter). The rig's controller acts on
// these instants, as a loop that reads the sensors, writes the command and
// logs a row does.
struct LoggerClock {
  double rate_Hz = 1e3;
  double period_s = 1e-3;  // the nominal interval, 1 / rate_Hz
  bool uniform = true;
  std::vector<double> t_s;  // irregular: from 0 to beyond any run of the log

  // The time from sample i - 1 to sample i.
  double Interval(std::size_t i) const { return uniform ? period_s : t_s[i] - t_s[i - 1]; }

  // The sample times from 0 to duration_s (inclusive, to round-off).
  std::vector<double> Until(double duration_s) const {
    if (uniform) return UniformTimes(0.0, duration_s, rate_Hz);
    std::vector<double> out;
    for (double t : t_s) {
      if (t > duration_s + 1e-9 * period_s) break;
      out.push_back(t);
    }
    return out;
  }

  // The first sample time at or after t. A t within round-off of a sample
  // time is kept when at or before it (that sample logs the new value either
  // way; the simulator applies a knot at or before an output time), else
  // moved onto it.
  double At(double t) const {
    const double round_off = 1e-6 * period_s;
    if (uniform) {
      const double rate = rate_Hz;
      const double nearest = std::round(t * rate);
      if (std::fabs(t * rate - nearest) < 1e-6) {
        const double sample_s = nearest / rate;
        return t <= sample_s ? t : sample_s;
      }
      return std::ceil(t * rate) / rate;
    }
    const auto at = std::lower_bound(t_s.begin(), t_s.end(), t - round_off);
    if (at == t_s.end()) return t;
    return std::fabs(*at - t) < round_off ? std::min(t, *at) : *at;
  }
};

// First-order lag of a signal sampled on `clock` and held between samples.
std::vector<double> Lag(const std::vector<double>& signal, const LoggerClock& clock, double tau_s) {
  std::vector<double> out = signal;
  if (tau_s > 0)
    ApplyFirstOrderLag([&clock](std::size_t i) { return clock.Interval(i); }, tau_s, &out);
  return out;
}

class RigBuilder {
 public:
  RigBuilder(const Parameters& truth, const Protocol& protocol, std::uint64_t seed)
      : truth_(truth),
        protocol_(protocol),
        seed_(seed),
        coefficients_(MakeActuatorCoefficients<double>(truth, ModelRegularization{})) {}

  Manifest MakeManifest(const std::string& unit_id) const {
    Manifest m;
    m.unit = unit_id;
    RigConstants& r = m.rig;
    r.gas = truth_.gas;
    r.supply_pressure_Pa = truth_.supply.supply_pressure_Pa;
    r.atmospheric_pressure_Pa = truth_.supply.atmospheric_pressure_Pa;
    r.air_density_kg_per_m3 = kAirDensity_kg_per_m3;
    r.bore_m = std::sqrt(4 * truth_.cylinder.area_1_m2 / kPi);
    r.rod_m = std::sqrt(4 * (truth_.cylinder.area_1_m2 - truth_.cylinder.area_2_m2) / kPi);
    r.stroke_m = truth_.cylinder.stroke_m;
    r.dead_volume_1_m3 = truth_.cylinder.dead_volume_1_m3;
    r.dead_volume_2_m3 = truth_.cylinder.dead_volume_2_m3;
    r.load_mass_kg = truth_.cylinder.load_mass_kg;
    r.orientation = truth_.cylinder.orientation;
    r.tube_length_m = truth_.pipeline.tube_length_m;
    r.position_origin = protocol_.position_origin;
    for (const auto& [name, sensor] : protocol_.sensors) {
      if (!sensor.declared) continue;
      SensorInfo info;
      if (sensor.tau_s > 0) info.tau_s = sensor.tau_s;
      if (sensor.sigma > 0) info.sigma = sensor.sigma;
      if (info.tau_s || info.sigma) m.sensors[name] = info;
    }
    return m;
  }

  std::vector<RigLog> MakeLogs(const Manifest& manifest) {
    std::vector<RigLog> logs;
    if (protocol_.valve) logs.push_back(ValveTest(manifest, logs.size()));
    for (double length : protocol_.tube_lengths_m) {
      logs.push_back(PipelineTest(manifest, length, logs.size()));
    }
    for (double level : protocol_.stroke_levels_V) {
      char id[32];
      std::snprintf(id, sizeof(id), "stroke-%03d", static_cast<int>(std::lround(level * 100)));
      std::string unique = id;  // two levels that round alike get a suffix
      for (int k = 2; std::any_of(logs.begin(), logs.end(),
                                  [&](const RigLog& l) { return l.entry.id == unique; });
           ++k) {
        unique = std::string(id) + "-" + std::to_string(k);
      }
      logs.push_back(ActuatorRun(manifest, unique, ExperimentKind::kStroke, StrokeCommand(level),
                                 logs.size()));
    }
    if (protocol_.paper_step) {
      logs.push_back(ActuatorRun(manifest, "step-1", ExperimentKind::kValidation,
                                 StrokeCommand(1.0), logs.size()));
    }
    if (protocol_.rich_profile) {
      logs.push_back(ActuatorRun(manifest, "profile-1", ExperimentKind::kValidation, RichProfile(),
                                 logs.size()));
    }
    return logs;
  }

 private:
  double Period() const { return 1.0 / protocol_.sample_rate_Hz; }

  // The clock of log `index`, long enough for duration_s: uniform, or each
  // interval the nominal one times 1 + U(-clock_jitter, clock_jitter) (its
  // own random stream: the noise is unchanged), stamped to 10 us.
  LoggerClock ClockOf(double duration_s, std::size_t index) const {
    LoggerClock clock;
    clock.rate_Hz = protocol_.sample_rate_Hz;
    clock.period_s = Period();
    if (!(protocol_.clock_jitter > 0)) return clock;
    clock.uniform = false;
    std::mt19937_64 rng(StreamSeed(seed_, index + kClockStream));
    std::uniform_real_distribution<double> stretch(1 - protocol_.clock_jitter,
                                                   1 + protocol_.clock_jitter);
    clock.t_s = {0.0};
    // Stamped to 10 us, which the logs' 7 significant digits write exactly
    // up to 100 s, so that a log's times are those the rig ran at.
    while (clock.t_s.back() <= duration_s + Period()) {
      const double next = clock.t_s.back() + Period() * stretch(rng);
      clock.t_s.push_back(std::max(std::round(next * 1e5), std::round(clock.t_s.back() * 1e5) + 1) /
                          1e5);
    }
    return clock;
  }

  // A signal through an instrument: its lag on the log's clock, then its
  // noise and ADC step (MeasureSignal).
  std::vector<double> Measure(const std::vector<double>& si, const LoggerClock& clock,
                              SensorModel sensor, std::uint64_t* rng) const {
    const std::vector<double> lagged = Lag(si, clock, sensor.tau_s);
    sensor.tau_s = 0;
    return MeasureSignal(lagged, clock.period_s, sensor, rng);
  }

  // The rig's controller changes its output at sample instants only (as it
  // ends a stroke leg on the next sample): a command time is moved to the
  // first sample at or after it, so that the logged u changes where the
  // command did. A knot moved onto the sample of an earlier one replaces it.
  CommandSignal OnSampleClock(const CommandSignal& command, const LoggerClock& clock) const {
    CommandSignal out;
    out.initial_V = command.initial_V;
    for (std::size_t i = 0; i < command.time_s.size(); ++i) {
      const double t = clock.At(command.time_s[i]);
      if (!out.time_s.empty() && t <= out.time_s.back()) {
        out.value_V.back() = command.value_V[i];
        continue;
      }
      out.time_s.push_back(t);
      out.value_V.push_back(command.value_V[i]);
    }
    return out;
  }

  SensorModel Sensor(const std::string& name) const {
    const auto found = protocol_.sensors.find(name);
    return found == protocol_.sensors.end() ? SensorModel{} : found->second;
  }

  // The sensor model for a flow channel, in mass flow, plus any hidden meter lag.
  std::vector<double> MeasureFlow(const std::string& name, const std::vector<double>& mass_flow,
                                  const LoggerClock& clock, double hidden_tau_s,
                                  std::uint64_t* rng) const {
    SensorModel sensor = Sensor(name);
    sensor.sigma *= kAirDensity_kg_per_m3;  // declared as standard volumetric flow
    sensor.quantization *= kAirDensity_kg_per_m3;
    return Measure(Lag(mass_flow, clock, hidden_tau_s), clock, sensor, rng);
  }

  // A column in the protocol's units for its quantity.
  void AddColumn(RigLog* log, const std::string& name, const std::string& unit,
                 const std::vector<double>& si, const Manifest& manifest) const {
    log->header.push_back(unit.empty() ? name : name + " [" + unit + "]");
    std::vector<double> written(si.size());
    for (std::size_t i = 0; i < si.size(); ++i) {
      written[i] = unit.empty() ? si[i]
                                : FromSI(unit, si[i], manifest.rig.atmospheric_pressure_Pa,
                                         kAirDensity_kg_per_m3);
    }
    log->columns.push_back(std::move(written));
  }

  RigLog NewLog(const std::string& id, ExperimentKind kind) const {
    RigLog log;
    log.entry.id = id;
    log.entry.kind = kind;
    log.entry.file = id + ".csv";
    log.comment =
        "synthetic data: pneumaid synth, seed " + std::to_string(seed_) + " (not a measurement)";
    return log;
  }

  // Mass flow [kg/s] through one valve of the truth at opening u, branch as
  // latched, from p_up to p_down; honours valve_deadzone.
  double ValveFlow(double opening_V, bool decreasing, double p_up, double p_down) const {
    const auto& c = coefficients_;
    const auto& branch = decreasing ? c.decreasing : c.increasing;
    const double gain = Kvp(EffectiveOpening(opening_V, c.deadzone_V), branch);
    return OrificeMassFlow(gain, p_up, p_down, c.orifice);
  }

  // The valve test's command: the staircase 0 -> 1 -> 0 V, or the ramp up and
  // down (a continuous command) when the protocol asks for one.
  int StaircaseSteps() const { return static_cast<int>(std::lround(1.0 / protocol_.valve_step_V)); }

  // The valve test's held levels: the protocol's list, or the staircase up
  // and down.
  std::vector<double> ValveLevels() const {
    if (!protocol_.valve_levels_V.empty()) return protocol_.valve_levels_V;
    std::vector<double> levels;
    const int steps = StaircaseSteps();
    for (int i = 0; i <= steps; ++i) levels.push_back(std::min(1.0, i * protocol_.valve_step_V));
    for (int i = steps - 1; i >= 0; --i) levels.push_back(i * protocol_.valve_step_V);
    return levels;
  }

  // How long the valve test runs: the ramp up and down, or every level held
  // valve_hold_s.
  double ValveDuration() const {
    if (protocol_.valve_ramp_s > 0) return 2 * protocol_.valve_ramp_s;
    return static_cast<double>(ValveLevels().size()) * protocol_.valve_hold_s;
  }

  std::pair<std::vector<double>, std::vector<double>> ValveCommand(const LoggerClock& clock) const {
    const double ramp_s = protocol_.valve_ramp_s;
    const auto t = clock.Until(ValveDuration());
    if (ramp_s > 0) {
      std::vector<double> u(t.size());
      for (std::size_t i = 0; i < t.size(); ++i)
        u[i] = std::clamp(1.0 - std::fabs(t[i] - ramp_s) / ramp_s, 0.0, 1.0);
      return {t, u};
    }
    const std::vector<double> levels = ValveLevels();
    std::vector<double> u(t.size());
    for (std::size_t i = 0; i < t.size(); ++i) {
      const auto level = std::min<std::size_t>(
          static_cast<std::size_t>(t[i] / protocol_.valve_hold_s), levels.size() - 1);
      u[i] = levels[level];
    }
    return {t, u};
  }

  RigLog ValveTest(const Manifest& manifest, std::size_t index) const {
    std::uint64_t rng = StreamSeed(seed_, index);
    const LoggerClock clock = ClockOf(ValveDuration(), index);
    const auto [t, u] = ValveCommand(clock);
    const std::vector<double> opening = Lag(u, clock, EffectValue(truth_, "valve_lag", "tau"));
    const double p_up = truth_.supply.supply_pressure_Pa,
                 p_down = truth_.supply.atmospheric_pressure_Pa;
    BranchLatch latch(kHysteresisThreshold_V);
    std::vector<double> q(t.size());
    for (std::size_t i = 0; i < t.size(); ++i) {
      latch.Update(u[i]);
      q[i] = ValveFlow(opening[i], latch.decreasing(), p_up, p_down);
    }
    RigLog log = NewLog(protocol_.valve_ramp_s > 0          ? "valve-ramp"
                        : !protocol_.valve_levels_V.empty() ? "valve-levels"
                                                            : "valve-staircase",
                        ExperimentKind::kValve);
    AddColumn(&log, "t", "s", t, manifest);
    AddColumn(&log, "u", "V", u, manifest);
    AddColumn(&log, "p_up", protocol_.pressure_unit,
              Measure(std::vector<double>(t.size(), p_up), clock, Sensor("p_up"), &rng), manifest);
    AddColumn(&log, "p_down", protocol_.pressure_unit,
              Measure(std::vector<double>(t.size(), p_down), clock, Sensor("p_down"), &rng),
              manifest);
    AddColumn(&log, "q", protocol_.flow_unit,
              MeasureFlow("q", q, clock, EffectValue(truth_, "flow_sensor_lag", "tau"), &rng),
              manifest);
    return log;
  }

  // The pipeline test's command at time t: the schedule's last knot at or
  // before t (0 V before the first), or the one step.
  double PipelineCommand(double t) const {
    if (protocol_.pipeline_schedule.empty()) {
      return t >= protocol_.pipeline_step_time_s ? protocol_.pipeline_command_V : 0.0;
    }
    double level = 0.0;
    for (const auto& [time, value] : protocol_.pipeline_schedule) {
      if (t >= time) level = value;
    }
    return level;
  }

  // delta at a tube length: the truth's measured law when it has one
  // (linear between its points, flat outside), else pipeline.delta.
  double DeltaAt(double length_m) const {
    const auto& table = truth_.pipeline.delta_by_length;
    if (table.empty()) return truth_.pipeline.delta_per_s;
    if (length_m <= table.front().tube_length_m) return table.front().delta_per_s;
    for (std::size_t i = 1; i < table.size(); ++i) {
      if (length_m <= table[i].tube_length_m) {
        const double w = (length_m - table[i - 1].tube_length_m) /
                         (table[i].tube_length_m - table[i - 1].tube_length_m);
        return (1 - w) * table[i - 1].delta_per_s + w * table[i].delta_per_s;
      }
    }
    return table.back().delta_per_s;
  }

  RigLog PipelineTest(const Manifest& manifest, double length_m, std::size_t index) const {
    std::uint64_t rng = StreamSeed(seed_, index);
    const LoggerClock clock = ClockOf(protocol_.pipeline_duration_s, index);
    const auto t = clock.Until(protocol_.pipeline_duration_s);
    std::vector<double> u(t.size()), q_in(t.size());
    const double p_up = truth_.supply.supply_pressure_Pa,
                 p_down = truth_.supply.atmospheric_pressure_Pa;
    for (std::size_t i = 0; i < t.size(); ++i) u[i] = PipelineCommand(t[i]);
    const auto opening = Lag(u, clock, EffectValue(truth_, "valve_lag", "tau"));
    BranchLatch latch(kHysteresisThreshold_V);
    for (std::size_t i = 0; i < t.size(); ++i) {
      latch.Update(u[i]);
      q_in[i] = ValveFlow(opening[i], latch.decreasing(), p_up, p_down);
    }
    // Eq. 5 between the tube's ends, exact for the flow held between samples.
    const std::vector<double> q_out = Lag(q_in, clock, 1.0 / DeltaAt(length_m));
    char id[32];
    std::snprintf(id, sizeof(id), "pipe-%03d", static_cast<int>(std::lround(length_m * 100)));
    RigLog log = NewLog(id, ExperimentKind::kPipeline);
    log.entry.tube_length_m = length_m;
    const double hidden = EffectValue(truth_, "flow_sensor_lag", "tau");
    AddColumn(&log, "t", "s", t, manifest);
    AddColumn(&log, "u", "V", u, manifest);
    AddColumn(&log, "q_in", protocol_.flow_unit, MeasureFlow("q_in", q_in, clock, hidden, &rng),
              manifest);
    AddColumn(&log, "q_out", protocol_.flow_unit, MeasureFlow("q_out", q_out, clock, hidden, &rng),
              manifest);
    return log;
  }

  // How an actuator run's command is built: a list of legs, each held until a
  // stroke end is reached (or for a fixed time), or a fixed command signal.
  struct ActuatorCommand {
    std::vector<double> leg_levels_V;  // held until 1 margin before the end it drives to
    CommandSignal fixed;               // used when leg_levels_V is empty
    double duration_s = 0.0;
  };

  ActuatorCommand StrokeCommand(double level) const {
    ActuatorCommand command;
    for (int cycle = 0; cycle < protocol_.stroke_cycles; ++cycle) {
      command.leg_levels_V.push_back(level);
      command.leg_levels_V.push_back(-level);
    }
    return command;
  }

  ActuatorCommand RichProfile() const {
    ActuatorCommand command;
    std::vector<std::pair<double, double>> steps = {
        {0.05, 0.5}, {0.6, -0.3}, {1.2, 0.8}, {1.7, -0.8}, {2.3, 0.0}};
    for (double t = 2.5; t < 4.0; t += Period()) steps.push_back({t, -0.5 + (t - 2.5) / 1.5 * 1.1});
    steps.push_back({4.0, -1.0});
    command.fixed = StepCommand(steps);
    command.duration_s = 4.6;
    return command;
  }

  Trajectory Run(const CommandSignal& command, const LoggerClock& clock, double duration_s) const {
    Trajectory run;
    SimulationOptions options;
    options.relative_tolerance = protocol_.mismatch.relative_tolerance;
    if (protocol_.mismatch.regularized_friction) {
      options.stick_slip = StickSlipTreatment::kRegularized;
      options.regularization.stick_velocity_m_per_s = protocol_.mismatch.stick_velocity_m_per_s;
    }
    const SimulationSummary summary =
        Simulate(truth_, command, RetractedAtRest(truth_), clock.Until(duration_s), options, &run);
    if (summary.status == SimulationStatus::kInvalidInput) {
      throw InputError("truth parameter set", 0, 0, summary.message);
    }
    if (!summary.ok()) throw std::runtime_error("synthetic rig: " + summary.message);
    return run;
  }

  // Holds each leg until the rod is `margin` before the end it drives to (the
  // rig's controller acts on the next sample) or max_leg has passed, then the
  // next leg; 0 V for 0.3 s at the end.
  Trajectory RunLegs(const std::vector<double>& levels, const LoggerClock& clock,
                     CommandSignal* command) const {
    const double half = 0.5 * truth_.cylinder.stroke_m;
    const double limit = half - protocol_.stroke_margin_m;
    std::vector<std::pair<double, double>> knots = {{clock.At(0.05), levels.front()}};
    for (std::size_t leg = 0; leg < levels.size(); ++leg) {
      const double start = knots.back().first;
      const double horizon = clock.At(start + protocol_.stroke_max_leg_s);
      const Trajectory run = Run(StepCommand(knots), clock, horizon);
      double end = horizon;
      for (std::size_t i = 0; i < run.size(); ++i) {
        const bool reached = levels[leg] > 0 ? run.x_m[i] >= limit : run.x_m[i] <= -limit;
        if (run.t_s[i] > start && reached) {
          // a sample time exactly (the controller acts on the next sample)
          const auto dwell =
              static_cast<std::size_t>(std::round(protocol_.stroke_dwell_s * clock.rate_Hz));
          if (i + 1 + dwell < run.size()) end = std::min(horizon, run.t_s[i + 1 + dwell]);
          break;
        }
      }
      knots.push_back({end, leg + 1 < levels.size() ? levels[leg + 1] : 0.0});
    }
    *command = StepCommand(knots);
    return Run(*command, clock, knots.back().first + 0.3);
  }

  RigLog ActuatorRun(const Manifest& manifest, const std::string& id, ExperimentKind kind,
                     const ActuatorCommand& spec, std::size_t index) const {
    std::uint64_t rng = StreamSeed(seed_, index);
    // Long enough for every leg held its longest, and the 0 V after.
    const double longest_s =
        spec.duration_s +
        static_cast<double>(spec.leg_levels_V.size()) * (protocol_.stroke_max_leg_s + 0.01) + 0.5;
    const LoggerClock clock = ClockOf(longest_s, index);
    CommandSignal command = OnSampleClock(spec.fixed, clock);
    const Trajectory run = spec.leg_levels_V.empty() ? Run(command, clock, spec.duration_s)
                                                     : RunLegs(spec.leg_levels_V, clock, &command);
    const double half = 0.5 * truth_.cylinder.stroke_m;
    const double origin_shift =
        protocol_.position_origin == PositionOrigin::kRetracted ? half : 0.0;
    std::vector<double> x = Measure(run.x_m, clock, Sensor("x"), &rng);
    for (double& value : x) value += origin_shift;
    RigLog log = NewLog(id, kind);
    AddColumn(&log, "t", "s", run.t_s, manifest);
    AddColumn(&log, "u", "V", run.u_V, manifest);
    AddColumn(&log, "x", protocol_.length_unit, x, manifest);
    AddColumn(&log, "p1", protocol_.pressure_unit, Measure(run.p1_Pa, clock, Sensor("p1"), &rng),
              manifest);
    AddColumn(&log, "p2", protocol_.pressure_unit, Measure(run.p2_Pa, clock, Sensor("p2"), &rng),
              manifest);
    // The simulator already applied any hidden flow_sensor_lag to q1, q2.
    AddColumn(&log, "q1", protocol_.flow_unit, MeasureFlow("q1", run.q1_kg_per_s, clock, 0.0, &rng),
              manifest);
    AddColumn(&log, "q2", protocol_.flow_unit, MeasureFlow("q2", run.q2_kg_per_s, clock, 0.0, &rng),
              manifest);
    DropRows(StreamSeed(seed_, index + kDroppedRowsStream), &log);
    return log;
  }

  // A lossy logger: each row but the first and last is lost with probability
  // Protocol::dropped_samples (its own random stream: the noise is unchanged).
  void DropRows(std::uint64_t stream, RigLog* log) const {
    if (!(protocol_.dropped_samples > 0) || log->columns.empty()) return;
    std::mt19937_64 rng(stream);
    std::bernoulli_distribution lost(protocol_.dropped_samples);
    const std::size_t rows = log->columns.front().size();
    std::vector<char> keep(rows, 1);
    for (std::size_t i = 1; i + 1 < rows; ++i) keep[i] = !lost(rng);
    for (auto& column : log->columns) {
      std::size_t kept = 0;
      for (std::size_t i = 0; i < rows; ++i) {
        if (keep[i]) column[kept++] = column[i];
      }
      column.resize(kept);
    }
  }

  const Parameters& truth_;
  const Protocol& protocol_;
  std::uint64_t seed_;
  ActuatorCoefficients<double> coefficients_;  // of the truth, for the valve and tube tests
};

bool PathMatches(const std::string& pattern, const std::string& path) {
  std::size_t p = 0, q = 0;
  while (p < pattern.size() && q < path.size()) {
    const std::size_t p_end = std::min(pattern.find('.', p), pattern.size());
    const std::size_t q_end = std::min(path.find('.', q), path.size());
    const std::string segment = pattern.substr(p, p_end - p);
    if (segment != "*" && segment != path.substr(q, q_end - q)) return false;
    p = p_end + 1;
    q = q_end + 1;
  }
  return p >= pattern.size() && q >= path.size();
}

}  // namespace

std::vector<double> MeasureSignal(const std::vector<double>& si, double sample_period_s,
                                  const SensorModel& sensor, std::uint64_t* rng_state) {
  LoggerClock clock;
  clock.period_s = sample_period_s;
  std::vector<double> out = Lag(si, clock, sensor.tau_s);
  if (rng_state == nullptr) return out;  // lag only
  std::mt19937_64 rng(*rng_state);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (double& value : out) {
    if (sensor.sigma > 0) value += sensor.sigma * noise(rng);
    if (sensor.quantization > 0)
      value = sensor.quantization * std::round(value / sensor.quantization);
  }
  *rng_state = rng();  // the next channel draws from where this one ended
  return out;
}

SyntheticUnit Synthesize(const Parameters& truth, const Protocol& protocol, std::uint64_t seed,
                         const std::string& unit_id) {
  const auto problems = Validate(truth);
  if (!problems.empty()) {
    throw InputError("truth parameter set", 0, 0,
                     problems.front().path + ": " + problems.front().message);
  }
  // Each leg drives to `margin` before an end: from mid-stroke, a margin of
  // half the stroke or more is reached before the rod moves, and every leg
  // would end at once.
  const bool has_strokes = !protocol.stroke_levels_V.empty();
  if (has_strokes && protocol.stroke_margin_m >= 0.5 * truth.cylinder.stroke_m) {
    char message[160];
    std::snprintf(message, sizeof(message),
                  "stroke.margin: %g mm, expected less than half the truth's stroke (%g mm)",
                  protocol.stroke_margin_m * 1e3, 0.5 * truth.cylinder.stroke_m * 1e3);
    throw InputError("protocol", 0, 0, message);
  }
  RigBuilder builder(truth, protocol, seed);
  SyntheticUnit unit;
  unit.truth = truth;
  unit.truth.unit = unit_id;
  unit.manifest = builder.MakeManifest(unit_id);
  unit.logs = builder.MakeLogs(unit.manifest);
  for (const RigLog& log : unit.logs) unit.manifest.experiments.push_back(log.entry);
  return unit;
}

std::map<std::string, std::string> UnitFiles(const SyntheticUnit& unit) {
  std::map<std::string, std::string> files;
  files["unit.yaml"] =
      "# synthetic unit: pneumaid synth (not a measurement)\n" + ManifestToYaml(unit.manifest);
  for (const RigLog& log : unit.logs) files[log.entry.file] = RigLogToCsv(log);
  files["truth.yaml"] =
      "# the truth behind this synthetic unit; for tests, never read by fitters\n" +
      ParamsToYaml(unit.truth);
  return files;
}

Parameters ApplySpread(const Parameters& params, const std::map<std::string, double>& fractions,
                       std::uint64_t seed) {
  Parameters out = params;
  std::mt19937_64 rng(StreamSeed(seed, 1000));
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (const auto& info : ScalarParameterTable()) {
    for (const auto& [pattern, fraction] : fractions) {
      if (PathMatches(pattern, info.path)) info.ref(out) *= 1.0 + fraction * uniform(rng);
    }
  }
  return out;
}

Parameters ApplyScale(const Parameters& params, const std::map<std::string, double>& factors) {
  Parameters out = params;
  for (const auto& [path, factor] : factors) {
    double value = 0;
    if (!GetParameter(out, path, &value)) {
      throw InputError("scale", 0, 0, "'" + path + "' names no parameter of the truth set");
    }
    SetParameter(&out, path, value * factor);
  }
  return out;
}

}  // namespace pneumaid
