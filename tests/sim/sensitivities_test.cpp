// CVODES forward sensitivities against central differences of the simulator:
// exact on a smooth trajectory, and across stick/slip and end-stop events
// with the documented jump conditions.
#include "pneumaid/sim/sensitivities.h"

#include <gtest/gtest.h>

#include <cmath>

#include "pneumaid/model/parameter_table.h"

namespace pneumaid {
namespace {

struct Case {
  Parameters params;
  CommandSignal command;
  InitialState initial;
  std::vector<double> times;
  SimulationOptions options;
  SensitivityOptions sensitivity;
};

SensitivityOptions FreeParameters(const Parameters& params, std::vector<std::string> paths) {
  SensitivityOptions s;
  s.parameter_paths = std::move(paths);
  for (const auto& path : s.parameter_paths) {
    double value = 0;
    EXPECT_TRUE(GetParameter(params, path, &value)) << path;
    s.parameter_scales.push_back(std::fabs(value));
  }
  return s;
}

const std::vector<std::string> kPaths = {
    "pipeline.delta",        "valve.increasing.q_max", "valve.decreasing.q_max",
    "friction.positive.Fs",  "friction.positive.Fd",   "friction.positive.b",
    "friction.positive.vs",  "friction.negative.Fs",   "friction.negative.Fd",
    "friction.negative.b",   "friction.negative.vs",   "cylinder.load_mass",
    "cylinder.dead_volume_1"};

// rtol 1e-10 with matching absolute tolerances, sensitivities in the error
// test: the integration error stays far below the differences compared.
void TightenTolerances(Case* c) {
  c->options.relative_tolerance = 1e-10;
  c->options.position_tolerance_m = 1e-13;
  c->options.velocity_tolerance_m_per_s = 1e-11;
  c->options.pressure_tolerance_Pa = 1e-4;
  c->options.mass_flow_tolerance_kg_per_s = 1e-15;
  c->sensitivity = FreeParameters(c->params, kPaths);
  c->sensitivity.error_control = true;
}

// A horizontal rod already sliding outwards at mid-stroke, driven by a half
// command for 40 ms: it never stops and never reaches an end.
Case SmoothSlide() {
  Case c;
  c.params.cylinder.orientation = Orientation::kHorizontal;
  c.params.friction.positive = {2.0, 1.5, 40.0, 0.01};
  c.params.friction.negative = {2.0, 1.5, 40.0, 0.01};
  c.command = StepCommand({{0.0, 0.4}});
  c.command.initial_V = 0.4;
  c.initial = {-0.02, 0.1, 2.6e5, 1.6e5};
  c.times = UniformTimes(0, 0.03, 1000);
  TightenTolerances(&c);
  return c;
}

// The paper's step: stick-slip on the way out and the end stop at 0.46 s.
Case PaperStep() {
  Case c;
  c.command = StepCommand({{0.0, 0.4}});
  c.initial = RetractedAtRest(c.params);
  c.times = UniformTimes(0, 0.6, 1000);
  TightenTolerances(&c);
  return c;
}

SimulationSummary SimulateCase(const Case& c, Trajectory* run, TrajectorySensitivities* sens) {
  return SimulateWithSensitivities(c.params, c.command, c.initial, c.times, c.options,
                                   c.sensitivity, run, sens);
}

Trajectory Run(const Case& c, const Parameters& params, SimulationSummary* summary = nullptr) {
  Trajectory out;
  const SimulationSummary s = Simulate(params, c.command, c.initial, c.times, c.options, &out);
  EXPECT_TRUE(s.ok()) << s.message;
  if (summary != nullptr) *summary = s;
  return out;
}

// Column j of a channel's sensitivity by central differences, and how many
// stick/slip events each side had.
Eigen::VectorXd CentralDifference(const Case& c, int j, std::vector<double> Trajectory::*channel,
                                  double relative_step, long* events_up, long* events_down) {
  const std::string& path = c.sensitivity.parameter_paths[j];
  const double step = relative_step * c.sensitivity.parameter_scales[j];
  double value = 0;
  GetParameter(c.params, path, &value);
  Parameters up = c.params, down = c.params;
  SetParameter(&up, path, value + step);
  SetParameter(&down, path, value - step);
  SimulationSummary su, sd;
  const Trajectory a = Run(c, up, &su), b = Run(c, down, &sd);
  *events_up = su.events;
  *events_down = sd.events;
  Eigen::VectorXd d(static_cast<Eigen::Index>(a.size()));
  for (size_t i = 0; i < a.size(); ++i) d[i] = ((a.*channel)[i] - (b.*channel)[i]) / (2 * step);
  return d;
}

struct ChannelCheck {
  const char* name;
  std::vector<double> Trajectory::*values;
  Eigen::MatrixXd TrajectorySensitivities::*derivatives;
  double scale;  // typical magnitude of the channel
};

const ChannelCheck kChannels[] = {
    {"x", &Trajectory::x_m, &TrajectorySensitivities::x, 0.025},
    {"p1", &Trajectory::p1_Pa, &TrajectorySensitivities::p1, 5e5},
    {"p2", &Trajectory::p2_Pa, &TrajectorySensitivities::p2, 5e5},
    {"q1", &Trajectory::q1_kg_per_s, &TrajectorySensitivities::q1, 1e-4},
    {"q2", &Trajectory::q2_kg_per_s, &TrajectorySensitivities::q2, 1e-4}};

// Largest |J - J_fd| / (|J_fd| + 1) over samples, with J made dimensionless:
// J = (s_p / channel scale) dy/dp (the bound |J - J_fd| <=
// 1e-4 (|J_fd| + s_p) in these units).
double WorstError(const Case& c, const Trajectory& run, const TrajectorySensitivities& sens,
                  double relative_step, double allowed, long* events_mismatch) {
  double worst = 0;
  *events_mismatch = 0;
  for (const ChannelCheck& channel : kChannels) {
    for (size_t j = 0; j < c.sensitivity.parameter_paths.size(); ++j) {
      long up = 0, down = 0;
      const Eigen::VectorXd fd =
          CentralDifference(c, static_cast<int>(j), channel.values, relative_step, &up, &down);
      if (up != down) ++*events_mismatch;
      const double unit = c.sensitivity.parameter_scales[j] / channel.scale;
      const Eigen::MatrixXd& exact = sens.*(channel.derivatives);
      for (Eigen::Index i = 0; i < fd.size(); ++i) {
        const double error = std::fabs(exact(i, static_cast<Eigen::Index>(j)) - fd[i]) * unit;
        const double bound = std::fabs(fd[i]) * unit + 1.0;
        if (!std::isfinite(error)) {
          ADD_FAILURE() << channel.name << " / " << c.sensitivity.parameter_paths[j] << " at t "
                        << run.t_s[static_cast<size_t>(i)] << ": not finite";
          return INFINITY;
        }
        if (error / bound > worst) {
          worst = error / bound;
          if (worst > allowed) {
            ADD_FAILURE() << channel.name << " / " << c.sensitivity.parameter_paths[j] << " at t "
                          << run.t_s[static_cast<size_t>(i)] << ": "
                          << exact(i, static_cast<Eigen::Index>(j)) << " vs " << fd[i];
          }
        }
      }
    }
  }
  return worst;
}

TEST(SensitivitiesTest, MatchCentralDifferencesOnASmoothSlide) {
  const Case c = SmoothSlide();
  Trajectory run;
  TrajectorySensitivities sens;
  const SimulationSummary summary = SimulateCase(c, &run, &sens);
  ASSERT_TRUE(summary.ok()) << summary.message;
  EXPECT_EQ(summary.events, 0) << "the slide must neither stick nor reach a stop";
  EXPECT_GT(run.x_m.back(), run.x_m.front() + 1e-3);
  long mismatch = 0;
  const double worst = WorstError(c, run, sens, 1e-4, 1e-4, &mismatch);
  std::cout << "worst |J - J_fd| / (|J_fd| + 1): " << worst << "\n";
  EXPECT_LE(worst, 1e-4);
}

// `c` simulated with its sensitivities (error-controlled) into `run` and
// `sens`: no stick event, and every column within 1e-4 of central
// differences (relative to |J_fd| + 1).
void ExpectMatchOnAnEventFreeRun(Case c, Trajectory* run, TrajectorySensitivities* sens) {
  c.sensitivity.error_control = true;
  const SimulationSummary summary = SimulateCase(c, run, sens);
  ASSERT_TRUE(summary.ok()) << summary.message;
  EXPECT_EQ(summary.events, 0);
  long mismatch = 0;
  const double worst = WorstError(c, *run, *sens, 1e-4, 1e-4, &mismatch);
  std::cout << "worst |J - J_fd| / (|J_fd| + 1): " << worst << "\n";
  EXPECT_LE(worst, 1e-4);
}

// The effects whose parameters reach the model through a gas-temperature
// state (heat_transfer) and through the implicit supply pressure
// (supply_droop, derivatives -f_theta / f'), with the base parameters they
// interact with, on the smooth slide.
TEST(SensitivitiesTest, MatchCentralDifferencesWithHeatTransferAndSupplyDroop) {
  Case c = SmoothSlide();
  c.params.effects["heat_transfer"] = {{"h", 0.05}};
  c.params.effects["supply_droop"] = {{"r", 3e8}};
  c.sensitivity = FreeParameters(c.params, {"effects.heat_transfer.h", "effects.supply_droop.r",
                                            "pipeline.delta", "friction.positive.b"});
  Trajectory run;
  TrajectorySensitivities sens;
  ASSERT_NO_FATAL_FAILURE(ExpectMatchOnAnEventFreeRun(c, &run, &sens));
  // Both effects move the outputs (their columns are not zero).
  EXPECT_GT(sens.p1.col(0).cwiseAbs().maxCoeff() * 0.05, 10.0);  // Pa per 100 % of h
  EXPECT_GT(sens.p1.col(1).cwiseAbs().maxCoeff() * 3e8, 10.0);   // Pa per 100 % of r
}

// stick_creep's v: a horizontal rod held at half its breakaway force with the
// valves shut creeps at a speed proportional to v (docs/effects.md), so its
// position's column is v's whole effect; with Fs, which the creep speed also
// sets, against central differences on the creeping hold.
TEST(SensitivitiesTest, MatchCentralDifferencesForAStickCreepHold) {
  Case c;
  c.params.cylinder.orientation = Orientation::kHorizontal;
  c.params.effects["stick_creep"] = {{"v", 1e-4}};
  const auto& cyl = c.params.cylinder;
  const double p2 = 2e5, atmosphere = c.params.supply.atmospheric_pressure_Pa;
  const double p1 = (0.5 * c.params.friction.positive.static_force_N + p2 * cyl.area_2_m2 +
                     atmosphere * (cyl.area_1_m2 - cyl.area_2_m2)) /
                    cyl.area_1_m2;
  c.initial = {0.0, 0.0, p1, p2};
  c.times = UniformTimes(0, 0.05, 1000);
  TightenTolerances(&c);
  c.sensitivity = FreeParameters(c.params, {"effects.stick_creep.v", "friction.positive.Fs"});
  Trajectory run;
  TrajectorySensitivities sens;
  ASSERT_NO_FATAL_FAILURE(ExpectMatchOnAnEventFreeRun(c, &run, &sens));
  EXPECT_GT(run.x_m.back(), 1e-6);  // it creeps
  // x grows with v: at the end of the hold dx/dv is about x / v.
  EXPECT_NEAR(sens.x.col(0)(sens.x.rows() - 1) * 1e-4, run.x_m.back(), 0.05 * run.x_m.back());
}

// Stick/slip and the end stop: the jump conditions make the sensitivities the
// derivatives of the event-driven outputs. Checked against central differences
// whose perturbed runs keep the same number of events. The bound is looser than
// on a smooth trajectory: each slide starts on the falling branch of the
// Stribeck curve, an unstable mode that amplifies the small errors of every
// event (measured worst: 1.8e-3 over 30 events; with the state resets alone and
// no event-time term the worst is 0.30).
TEST(SensitivitiesTest, MatchCentralDifferencesAcrossStickSlipAndTheEndStop) {
  const Case c = PaperStep();
  Trajectory run;
  TrajectorySensitivities sens;
  const SimulationSummary summary = SimulateCase(c, &run, &sens);
  ASSERT_TRUE(summary.ok()) << summary.message;
  EXPECT_GT(summary.events, 10);
  EXPECT_DOUBLE_EQ(run.x_m.back(), 0.5 * c.params.cylinder.stroke_m);
  long mismatch = 0;
  const double worst = WorstError(c, run, sens, 1e-5, 5e-3, &mismatch);
  std::cout << "worst |J - J_fd| / (|J_fd| + 1): " << worst << ", " << mismatch
            << " perturbations changed the event count\n";
  EXPECT_EQ(mismatch, 0);
}

// d(channel)/d(initial p_k) by central differences, k = 1 or 2.
Eigen::VectorXd InitialPressureDifference(const Case& c, int k,
                                          std::vector<double> Trajectory::*channel) {
  const double step = 1e-4 * (k == 1 ? c.initial.p1_Pa : c.initial.p2_Pa);
  Case up = c, down = c;
  (k == 1 ? up.initial.p1_Pa : up.initial.p2_Pa) += step;
  (k == 1 ? down.initial.p1_Pa : down.initial.p2_Pa) -= step;
  const Trajectory a = Run(up, c.params), b = Run(down, c.params);
  Eigen::VectorXd d(static_cast<Eigen::Index>(a.size()));
  for (size_t i = 0; i < a.size(); ++i) d[i] = ((a.*channel)[i] - (b.*channel)[i]) / (2 * step);
  return d;
}

// The initial pressures' columns (after the parameters') against central
// differences of the start, with the bound of the parameters' (scale: the
// pressure itself).
TEST(SensitivitiesTest, InitialPressureColumnsMatchCentralDifferences) {
  Case c = SmoothSlide();
  c.sensitivity = FreeParameters(c.params, {"friction.positive.Fd"});
  c.sensitivity.error_control = true;
  c.sensitivity.initial_pressures = true;
  ASSERT_EQ(c.sensitivity.Columns(), 3);
  Trajectory run;
  TrajectorySensitivities sens;
  const SimulationSummary summary = SimulateCase(c, &run, &sens);
  ASSERT_TRUE(summary.ok()) << summary.message;
  double worst = 0;
  for (const ChannelCheck& channel : kChannels) {
    const Eigen::MatrixXd& exact = sens.*(channel.derivatives);
    ASSERT_EQ(exact.cols(), 3);
    for (int k = 1; k <= 2; ++k) {
      const Eigen::VectorXd fd = InitialPressureDifference(c, k, channel.values);
      const double unit = (k == 1 ? c.initial.p1_Pa : c.initial.p2_Pa) / channel.scale;
      for (Eigen::Index i = 0; i < fd.size(); ++i) {
        const double error = std::fabs(exact(i, k) - fd[i]) * unit;
        worst = std::max(worst, error / (std::fabs(fd[i]) * unit + 1.0));
      }
    }
  }
  std::cout << "worst |J - J_fd| / (|J_fd| + 1): " << worst << "\n";
  EXPECT_LE(worst, 1e-4);
  // They are not zero: the start matters.
  EXPECT_GT(sens.x.col(1).cwiseAbs().maxCoeff() * c.initial.p1_Pa, 1e-5);
}

// Fewer free parameters are carried in fewer Jet lanes (2, 4, 10 or 16): the
// lane count must not change a column beyond the corrector's tolerance (its
// convergence test spans all the sensitivities carried). The smooth slide,
// each subset against the same parameters among all 13.
TEST(SensitivitiesTest, EveryLaneCountGivesTheSameColumns) {
  Case all = SmoothSlide();
  all.sensitivity.error_control = false;  // the same steps whatever the count
  Trajectory run;
  TrajectorySensitivities reference;
  ASSERT_TRUE(SimulateWithSensitivities(all.params, all.command, all.initial, all.times,
                                        all.options, all.sensitivity, &run, &reference)
                  .ok());
  for (const size_t count : {1u, 3u, 7u}) {
    Case subset = all;
    subset.sensitivity = FreeParameters(all.params, {kPaths.begin(), kPaths.begin() + count});
    subset.sensitivity.error_control = false;
    TrajectorySensitivities sens;
    ASSERT_TRUE(SimulateWithSensitivities(subset.params, subset.command, subset.initial,
                                          subset.times, subset.options, subset.sensitivity, &run,
                                          &sens)
                    .ok());
    for (const ChannelCheck& channel : kChannels) {
      const Eigen::MatrixXd& expected = reference.*(channel.derivatives);
      const Eigen::MatrixXd& got = sens.*(channel.derivatives);
      ASSERT_EQ(got.cols(), static_cast<Eigen::Index>(count));
      for (Eigen::Index j = 0; j < got.cols(); ++j) {
        const double unit =
            all.sensitivity.parameter_scales[static_cast<size_t>(j)] / channel.scale;
        const double worst = ((got.col(j) - expected.col(j)) * unit).cwiseAbs().maxCoeff();
        EXPECT_LE(worst, 1e-10) << count << " parameters, " << channel.name << " / " << kPaths[j];
      }
    }
  }
}

TEST(SensitivitiesTest, RefusesUnknownParametersAndMissingScales) {
  Case c = SmoothSlide();
  Trajectory run;
  TrajectorySensitivities sens;
  c.sensitivity.parameter_paths[0] = "pipeline.nonsense";
  SimulationSummary s = SimulateWithSensitivities(c.params, c.command, c.initial, c.times,
                                                  c.options, c.sensitivity, &run, &sens);
  EXPECT_EQ(s.status, SimulationStatus::kInvalidInput);
  EXPECT_NE(s.message.find("pipeline.nonsense"), std::string::npos) << s.message;
  c = SmoothSlide();
  c.sensitivity.parameter_scales.pop_back();
  s = SimulateWithSensitivities(c.params, c.command, c.initial, c.times, c.options, c.sensitivity,
                                &run, &sens);
  EXPECT_EQ(s.status, SimulationStatus::kInvalidInput);
}

}  // namespace
}  // namespace pneumaid
