#include "pneumaid/sim/simulate.h"

#include <ceres/jet.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>

#include "cvode_handles.h"
#include "fast_kernels.h"
#include "pneumaid/model/effects.h"
#include "pneumaid/model/parameter_table.h"
#include "pneumaid/sim/sensitivities.h"

namespace pneumaid {
namespace {

using JetN = ceres::Jet<double, kMaxStates>;

inline double Value(double x) { return x; }
template <int N>
double Value(const ceres::Jet<double, N>& x) {
  return x.a;
}

class ParameterJets;  // below: the model's derivatives in the free parameters
class ValveCommandTracker;

// Everything the CVODE callbacks need. The command changes between segments;
// the layout and coefficients are fixed for the run.
struct ModelData {
  ActuatorLayout layout;
  ActuatorCoefficients<double> coefficients;
  ActuatorCoefficients<JetN> jet_coefficients;
  ValveCommand command;
  MotionMode motion = MotionMode::kRegularized;
  double supply_pressure_Pa = 0.0;
  double breakaway_margin_N = 0.0;
  // A sliding rod counts as stopped once v has crossed zero by this much:
  // right after a restart v is only known to within its tolerance.
  double reversal_velocity_m_per_s = 0.0;
  std::string last_solver_message;
  // Parameter sensitivities: how many (0: none), and the model's
  // derivatives with respect to each (null without).
  int parameter_count = 0;
  std::unique_ptr<const ParameterJets> parameter_jets;
};

// What a run with sensitivities evaluates in Jets whose derivative j is taken
// with respect to free parameter j (the coefficients carry dc/dp_j, the state
// carries s_j = dy/dp_j). Implemented for a few lane counts (LanedJets below):
// Jet arithmetic is the part of a sensitivity step that grows with the lanes,
// so a 2-parameter fit should not pay for 16.
class ParameterJets {
 public:
  virtual ~ParameterJets() = default;
  // CVODES' sensitivity right-hand sides, all at once: s_j' = f_y s_j + f_p_j.
  // Returns 1 (recoverable) on a non-finite rate.
  virtual int Rates(const ModelData& data, const double* y, const N_Vector* s,
                    N_Vector* rates) const = 0;
  // The total derivative g_y s_j + g_p_j of switching function `fired`.
  virtual void SwitchingDerivatives(const ModelData& data, const double* y, const N_Vector* s,
                                    int fired, double* dg_dp) const = 0;
  // Row `row` of the output sensitivities.
  virtual void AppendOutputs(const ModelData& data, const double* y, const N_Vector* s,
                             Eigen::Index row, TrajectorySensitivities* out) const = 0;
  // dy(t0)/dp_j: the chamber states and settled lags depend on the
  // parameters even though the initial pressures and position do not.
  virtual std::vector<std::vector<double>> Initial(
      const ModelData& data, const InitialState& initial, const CommandSignal& command,
      const ValveCommandTracker& fresh, const ValveCommand& initial_command, double t0) const = 0;
};

// CVODES sensitivity right-hand side callback. Never throws.
int SensitivityRightHandSide(int, sunrealtype, N_Vector y, N_Vector, N_Vector* sensitivities,
                             N_Vector* rates, void* user_data, N_Vector, N_Vector) {
  const auto* data = static_cast<const ModelData*>(user_data);
  return data->parameter_jets->Rates(*data, N_VGetArrayPointer(y), sensitivities, rates);
}

// CVODE right-hand side. Returns 1 (recoverable: CVODE retries with a smaller
// step) on a non-finite rate; never throws. (Pressures are positive by
// construction of the chamber state.)
int RightHandSide(sunrealtype, N_Vector y, N_Vector ydot, void* user_data) {
  const auto* data = static_cast<const ModelData*>(user_data);
  const double* state = N_VGetArrayPointer(y);
  double* rate = N_VGetArrayPointer(ydot);
  ActuatorDerivatives(data->layout, data->coefficients, data->command, data->motion, state, rate,
                      static_cast<ActuatorOutputs<double>*>(nullptr));
  for (int i = 0; i < data->layout.size; ++i) {
    if (!std::isfinite(rate[i])) return 1;
  }
  return 0;
}

// Exact dense Jacobian df/dy by forward-mode automatic differentiation.
int Jacobian(sunrealtype, N_Vector y, N_Vector, SUNMatrix jacobian, void* user_data, N_Vector,
             N_Vector, N_Vector) {
  const auto* data = static_cast<const ModelData*>(user_data);
  const int n = data->layout.size;
  const double* state = N_VGetArrayPointer(y);
  JetN jet_state[kMaxStates];
  JetN jet_rate[kMaxStates];
  for (int i = 0; i < n; ++i) jet_state[i] = JetN(state[i], i);
  ActuatorDerivatives(data->layout, data->jet_coefficients, data->command, data->motion, jet_state,
                      jet_rate, static_cast<ActuatorOutputs<JetN>*>(nullptr));
  for (int row = 0; row < n; ++row) {
    for (int col = 0; col < n; ++col) {
      const double value = jet_rate[row].v[col];
      if (!std::isfinite(value)) return 1;
      SM_ELEMENT_D(jacobian, row, col) = value;
    }
  }
  return 0;
}

// Within a nanometre of an end stop: a rod resting there is set exactly on
// it, this margin only absorbs round-off.
constexpr double kAtStop_m = 1e-9;

bool AtExtendedStop(const ModelData& data, double position_m) {
  return position_m >= data.coefficients.end_stop.half_stroke_m - kAtStop_m;
}
bool AtRetractedStop(const ModelData& data, double position_m) {
  return position_m <= -data.coefficients.end_stop.half_stroke_m + kAtStop_m;
}

// Stick/slip and end-stop switching surfaces. Stuck: the driving force
// reaches the breakaway force plus a margin (the switching hysteresis) in a
// direction the rod can move. Sliding: the velocity returns to zero (g0) or
// the rod reaches the end of the stroke (g1). Templated so that the event
// sensitivities can differentiate them.
template <typename T>
void SwitchingValues(const ModelData& data, const ActuatorCoefficients<T>& c, const T* y, T* g) {
  const T half_stroke = c.end_stop.half_stroke_m;
  const T margin(data.breakaway_margin_N);
  const T reversal(data.reversal_velocity_m_per_s);
  switch (data.motion) {
    case MotionMode::kStuck: {
      const ChamberPressures<T> p = DecodeChambers(c, y);
      const T force = DrivingForce(c, y, p);
      const double x = Value(y[kPosition]);
      g[0] = AtExtendedStop(data, x) ? T(-1.0) : force - BreakawayForce(c, p, +1.0) - margin;
      g[1] = AtRetractedStop(data, x) ? T(1.0) : force + BreakawayForce(c, p, -1.0) + margin;
      break;
    }
    case MotionMode::kSlidingPositive:
      g[0] = y[kVelocity] + reversal;
      g[1] = half_stroke - y[kPosition];
      break;
    case MotionMode::kSlidingNegative:
      g[0] = y[kVelocity] - reversal;
      g[1] = y[kPosition] + half_stroke;
      break;
    case MotionMode::kRegularized:
      g[0] = g[1] = T(1.0);
      break;
  }
}

// CVODE root function. Never throws.
int SwitchingFunctions(sunrealtype, N_Vector y, sunrealtype* g, void* user_data) {
  const auto* data = static_cast<const ModelData*>(user_data);
  SwitchingValues(*data, data->coefficients, N_VGetArrayPointer(y), g);
  return 0;
}

// The motion mode for a rod at rest at state y: held by static friction
// unless the driving force exceeds the breakaway force (plus the margin), and
// held by an end stop it is pushed against.
MotionMode ModeAtRest(const ModelData& data, const double* y) {
  const auto& c = data.coefficients;
  const ChamberPressures<double> p = DecodeChambers(c, y);
  const double force = DrivingForce(c, y, p);
  if (!AtExtendedStop(data, y[kPosition]) &&
      force > BreakawayForce(c, p, +1.0) + data.breakaway_margin_N) {
    return MotionMode::kSlidingPositive;
  }
  if (!AtRetractedStop(data, y[kPosition]) &&
      force < -BreakawayForce(c, p, -1.0) - data.breakaway_margin_N) {
    return MotionMode::kSlidingNegative;
  }
  return MotionMode::kStuck;
}

MotionMode InitialMode(const ModelData& data, const double* y) {
  if (y[kVelocity] > 0) return MotionMode::kSlidingPositive;
  if (y[kVelocity] < 0) return MotionMode::kSlidingNegative;
  return ModeAtRest(data, y);
}

// Keeps CVODE's error text for the summary instead of printing it.
void CaptureSolverMessage(int, const char* module, const char* function, char* message,
                          void* user_data) {
  auto* data = static_cast<ModelData*>(user_data);
  data->last_solver_message = std::string(module) + "::" + function + ": " + message;
}

using internal::CheckAllocated;
using internal::CheckFlag;

// One CVODES BDF integrator over the actuator ODE.
class Integrator {
 public:
  Integrator(ModelData* data, const SimulationOptions& options, double t0, const double* y0)
      : data_(data), size_(data->layout.size) {
    SUNContext raw_context = nullptr;
    CheckFlag(SUNContext_Create(nullptr, &raw_context), "SUNContext_Create");
    context_.reset(raw_context);
    state_.reset(CheckAllocated(N_VNew_Serial(size_, context_.get()), "N_VNew_Serial"));
    // Fused and vector-array operations: the sensitivities use them heavily.
    CheckFlag(N_VEnableFusedOps_Serial(state_.get(), SUNTRUE), "N_VEnableFusedOps_Serial");
    internal::InstallFastVectorKernels(state_.get());
    tolerances_.reset(CheckAllocated(N_VClone(state_.get()), "N_VClone"));
    for (int i = 0; i < size_; ++i) N_VGetArrayPointer(state_.get())[i] = y0[i];
    FillAbsoluteTolerances(options);
    memory_.reset(CheckAllocated(CVodeCreate(CV_BDF, context_.get()), "CVodeCreate"));
    void* mem = memory_.get();
    CheckFlag(CVodeInit(mem, RightHandSide, t0, state_.get()), "CVodeInit");
    CheckFlag(CVodeSetUserData(mem, data_), "CVodeSetUserData");
    CheckFlag(CVodeSetErrHandlerFn(mem, CaptureSolverMessage, data_), "CVodeSetErrHandlerFn");
    CheckFlag(CVodeSVtolerances(mem, options.relative_tolerance, tolerances_.get()),
              "CVodeSVtolerances");
    relative_tolerance_ = options.relative_tolerance;
    matrix_.reset(CheckAllocated(SUNDenseMatrix(size_, size_, context_.get()), "SUNDenseMatrix"));
    internal::InstallFastMatrixKernels(matrix_.get());
    solver_.reset(
        CheckAllocated(internal::NewFastDenseSolver(size_, context_.get()), "NewFastDenseSolver"));
    CheckFlag(CVodeSetLinearSolver(mem, solver_.get(), matrix_.get()), "CVodeSetLinearSolver");
    CheckFlag(CVodeSetJacFn(mem, Jacobian), "CVodeSetJacFn");
    CheckFlag(CVodeSetMaxNumSteps(mem, 100000), "CVodeSetMaxNumSteps");
    if (data_->motion != MotionMode::kRegularized) {
      CheckFlag(CVodeRootInit(mem, 2, SwitchingFunctions), "CVodeRootInit");
      // A switching surface met at the start of a segment (zero at t0) is
      // ignored by CVODE until it moves away: no Zeno loop at breakaway.
      CheckFlag(CVodeSetNoInactiveRootWarn(mem), "CVodeSetNoInactiveRootWarn");
    }
  }

  double* state() { return N_VGetArrayPointer(state_.get()); }

  // Turns on forward sensitivities for data->parameter_count columns (their
  // typical magnitudes in `scales`), starting from initial[j][i] = dy_i(t0)/dp_j.
  void EnableSensitivities(const std::vector<std::vector<double>>& initial,
                           const SensitivityOptions& options, const std::vector<double>& scales) {
    const int count = data_->parameter_count;
    sensitivities_ = internal::VectorArray(
        CheckAllocated(N_VCloneVectorArray(count, state_.get()), "N_VCloneVectorArray"), count);
    for (int j = 0; j < count; ++j) {
      for (int i = 0; i < size_; ++i)
        N_VGetArrayPointer(sensitivities_.get()[j])[i] = initial[j][i];
    }
    void* mem = memory_.get();
    CheckFlag(
        CVodeSensInit(mem, count, CV_STAGGERED, SensitivityRightHandSide, sensitivities_.get()),
        "CVodeSensInit");
    std::vector<double> pbar = scales;  // CVODES takes a non-const array
    CheckFlag(CVodeSetSensParams(mem, nullptr, pbar.data(), nullptr), "CVodeSetSensParams");
    if (options.tolerance_factor == 1.0) {
      CheckFlag(CVodeSensEEtolerances(mem), "CVodeSensEEtolerances");
    } else {
      // The state's tolerances per unit of each parameter's scale, widened.
      internal::VectorArray absolute(
          CheckAllocated(N_VCloneVectorArray(count, state_.get()), "N_VCloneVectorArray"), count);
      for (int j = 0; j < count; ++j) {
        N_VScale(options.tolerance_factor / scales[j], tolerances_.get(), absolute.get()[j]);
      }
      CheckFlag(CVodeSensSVtolerances(mem, options.tolerance_factor * relative_tolerance_,
                                      absolute.get()),
                "CVodeSensSVtolerances");
    }
    CheckFlag(CVodeSetSensErrCon(mem, options.error_control ? SUNTRUE : SUNFALSE),
              "CVodeSetSensErrCon");
    sensitivities_current_ = true;  // they are the initial values until CVODE steps
  }

  // dy/dp_j at the time CVODE last returned (nullptr without sensitivities).
  // Before the first step after a (re)start the vectors hold the values given
  // to CVODES (CVodeGetSens would divide by the step size, still zero).
  const N_Vector* Sensitivities() {
    if (sensitivities_.get() == nullptr) return nullptr;
    if (!sensitivities_current_) {
      double t = 0;
      if (CVodeGetSens(memory_.get(), &t, sensitivities_.get()) < 0) return nullptr;
      sensitivities_current_ = true;
    }
    return sensitivities_.get();
  }

  // Integrates to `target`, never past `stop`, switching the motion mode at
  // every stick/slip event on the way. Returns CVODE's flag (< 0 fails).
  int AdvanceTo(double target, double stop) {
    void* mem = memory_.get();
    int flag = CVodeSetStopTime(mem, stop);
    while (flag >= 0) {
      double reached = 0;
      flag = CVode(mem, target, state_.get(), &reached, CV_NORMAL);
      sensitivities_current_ = false;
      if (flag != CV_ROOT_RETURN) return flag;
      SwitchMotionMode();
      flag = Restart(reached);
      if (flag >= 0) flag = CVodeSetStopTime(mem, stop);
    }
    return flag;
  }

  long events() const { return events_; }

  // Restarts at low order after a jump of the right-hand side at time t
  // (the sensitivities carry over, with any jump SwitchMotionMode applied).
  int Restart(double t) {
    const N_Vector* sensitivities = Sensitivities();
    banked_ = Counters();  // CVodeReInit zeroes CVODE's counters
    ++restarts_;
    int flag = CVodeReInit(memory_.get(), t, state_.get());
    if (flag >= 0 && sensitivities != nullptr) {
      flag = CVodeSensReInit(memory_.get(), CV_STAGGERED, sensitivities_.get());
    }
    sensitivities_current_ = sensitivities != nullptr;  // the restart values
    return flag;
  }

  // At a root of SwitchingFunctions: stuck -> sliding in the direction that
  // broke away; sliding -> stuck, or reversal, once v reaches zero; sliding
  // into an end stop -> an inelastic impact, the rod rests at the stop.
  void SwitchMotionMode() {
    ++events_;
    double* y = state();
    int roots[2] = {0, 0};
    CVodeGetRootInfo(memory_.get(), roots);
    const int fired = roots[0] != 0 ? 0 : 1;
    EventJump jump;
    const bool with_sensitivities = Sensitivities() != nullptr;
    if (with_sensitivities) jump = EventTimeSensitivities(fired);
    if (data_->motion == MotionMode::kStuck) {
      data_->motion = fired == 0 ? MotionMode::kSlidingPositive : MotionMode::kSlidingNegative;
    } else {
      if (fired == 1) {
        const double half_stroke = data_->coefficients.end_stop.half_stroke_m;
        y[kPosition] = data_->motion == MotionMode::kSlidingPositive ? half_stroke : -half_stroke;
        jump.reset_position = true;
      }
      y[kVelocity] = 0.0;
      jump.reset_velocity = true;
      data_->motion = ModeAtRest(*data_, y);
    }
    if (with_sensitivities) ApplySensitivityJump(jump);
  }

 private:
  // What an event does to the sensitivities: the right-hand side before it,
  // d(event time)/dp, and which states the reset overwrites.
  struct EventJump {
    double rate_before[kMaxStates] = {};
    double time_derivative[kMaxSensitivityParameters] = {};
    bool reset_position = false, reset_velocity = false;
  };

  // tau_p = -(g_y s + g_p) / (g_y f) for the switching function that fired.
  EventJump EventTimeSensitivities(int fired) {
    EventJump jump;
    const double* y = state();
    const int count = data_->parameter_count;
    ActuatorDerivatives(data_->layout, data_->coefficients, data_->command, data_->motion, y,
                        jump.rate_before, static_cast<ActuatorOutputs<double>*>(nullptr));
    JetN along_state[kMaxStates];
    for (int i = 0; i < size_; ++i) along_state[i] = JetN(y[i], i);
    JetN g_state[2];
    SwitchingValues(*data_, data_->jet_coefficients, along_state, g_state);
    double g_rate = 0;  // dg/dt along the trajectory
    for (int i = 0; i < size_; ++i) g_rate += g_state[fired].v[i] * jump.rate_before[i];
    // A grazing event (dg/dt ~ 0) has no well-defined time derivative; its
    // jump is left out (the rod touches the surface without crossing it).
    if (!(std::fabs(g_rate) > 1e-12)) return jump;
    double dg_dp[kMaxSensitivityParameters];
    data_->parameter_jets->SwitchingDerivatives(*data_, y, sensitivities_.get(), fired, dg_dp);
    for (int j = 0; j < count; ++j) jump.time_derivative[j] = -dg_dp[j] / g_rate;
    return jump;
  }

  // s+ = H (s- + f- tau_p) - f+ tau_p, with H zeroing the reset states.
  void ApplySensitivityJump(const EventJump& jump) {
    double rate_after[kMaxStates];
    ActuatorDerivatives(data_->layout, data_->coefficients, data_->command, data_->motion, state(),
                        rate_after, static_cast<ActuatorOutputs<double>*>(nullptr));
    for (int j = 0; j < data_->parameter_count; ++j) {
      double* s = N_VGetArrayPointer(sensitivities_.get()[j]);
      const double tau = jump.time_derivative[j];
      for (int i = 0; i < size_; ++i) {
        const bool reset =
            (i == kPosition && jump.reset_position) || (i == kVelocity && jump.reset_velocity);
        s[i] = (reset ? 0.0 : s[i] + jump.rate_before[i] * tau) - rate_after[i] * tau;
      }
    }
  }

 public:
  // Work done so far, restarts included.
  SimulationSummary Counters() const {
    void* mem = memory_.get();
    SimulationSummary total = banked_;
    long value = 0;
    CVodeGetNumSteps(mem, &value);
    total.steps += value;
    CVodeGetNumRhsEvals(mem, &value);
    total.rhs_evaluations += value;
    CVodeGetNumJacEvals(mem, &value);
    total.jacobian_evaluations += value;
    CVodeGetNumErrTestFails(mem, &value);
    total.error_test_failures += value;
    CVodeGetNumNonlinSolvConvFails(mem, &value);
    total.convergence_failures += value;
    total.restarts = restarts_;
    total.events = events_;
    return total;
  }

 private:
  void FillAbsoluteTolerances(const SimulationOptions& options) {
    double* atol = N_VGetArrayPointer(tolerances_.get());
    const ActuatorLayout& layout = data_->layout;
    atol[kPosition] = options.position_tolerance_m;
    atol[kVelocity] = options.velocity_tolerance_m_per_s;
    // sigma = ln p + ...: an error d sigma is a relative pressure error, so
    // the pressure tolerance is taken relative to the highest pressure, the
    // supply (at least as strict as the absolute tolerance in Pa).
    const double sigma_tolerance = options.pressure_tolerance_Pa / data_->supply_pressure_Pa;
    atol[kChamber1] = sigma_tolerance;
    atol[kChamber2] = sigma_tolerance;
    for (int i = 4; i < size_; ++i) atol[i] = options.mass_flow_tolerance_kg_per_s;
    if (layout.valve_lag) {
      for (int i = 0; i < kValveCount; ++i) {
        atol[layout.opening_begin + i] = options.opening_tolerance_V;
      }
    }
  }

  ModelData* data_;
  int size_;
  internal::ContextPtr context_;  // first: destroyed last
  internal::VectorPtr state_;
  internal::VectorPtr tolerances_;
  internal::MatrixPtr matrix_;
  internal::LinearSolverPtr solver_;
  internal::VectorArray sensitivities_;  // empty without; before memory_: outlives CVODES
  internal::CvodePtr memory_;
  bool sensitivities_current_ = false;
  double relative_tolerance_ = 0;
  SimulationSummary banked_;
  long restarts_ = 0;
  long events_ = 0;
};

// Turns command values into valve commands, keeping each valve's hysteresis
// latch across segments.
class ValveCommandTracker {
 public:
  ValveCommandTracker(ValveBranchMode mode, double threshold_V)
      : mode_(mode),
        latches_{BranchLatch(threshold_V), BranchLatch(threshold_V), BranchLatch(threshold_V),
                 BranchLatch(threshold_V)} {}

  ValveCommand Next(double command_V) {
    ValveCommand command;
    command.opening = OpeningsForCommand(command_V);
    for (int i = 0; i < kValveCount; ++i) {
      latches_[i].Update(command.opening[i]);
      command.decreasing_branch[i] = mode_ == ValveBranchMode::kHysteresis
                                         ? latches_[i].decreasing()
                                         : mode_ == ValveBranchMode::kDecreasing;
    }
    return command;
  }

 private:
  ValveBranchMode mode_;
  std::array<BranchLatch, kValveCount> latches_;
};

// Relaxes the lags driven by the command alone over dt seconds of a held
// command: exact exponentials.
template <typename T>
void RelaxCommandLags(const ActuatorLayout& layout, const ActuatorCoefficients<T>& c,
                      const ValveCommand& command, double dt, T* y) {
  using std::exp;
  if (!(dt > 0)) return;
  if (layout.valve_lag) {
    const T keep = exp(T(-dt) / c.valve_lag_tau_s);
    for (int i = 0; i < kValveCount; ++i) {
      T& opening = y[layout.opening_begin + i];
      opening = T(command.opening[i]) + (opening - T(command.opening[i])) * keep;
    }
  }
  if (layout.conductance_lag) {
    const auto gain = ValveGains(c, command, ValveOpeningsInUse(layout, command, y));
    const T keep = exp(T(-dt) * c.pipeline_delta_per_s);
    for (int i = 0; i < kValveCount; ++i) {
      T& lagged = y[layout.conductance_begin + i];
      lagged = gain[i] + (lagged - gain[i]) * keep;
    }
  }
}

// The lag states at t0 (InitialState::lag_history_from_s): settled for the
// command at `from`, then relaxed through every knot up to t0. `tracker` is
// fresh; it is advanced as the run's own tracker would be.
template <typename T>
void ReplayLagHistory(const ActuatorLayout& layout, const ActuatorCoefficients<T>& c,
                      const CommandSignal& command, ValveCommandTracker tracker, double from,
                      double t0, T* y) {
  ValveCommand current = tracker.Next(command.initial_V);
  size_t knot = 0;
  for (; knot < command.time_s.size() && command.time_s[knot] <= from; ++knot) {
    current = tracker.Next(command.value_V[knot]);
  }
  SetLagStatesToEquilibrium(layout, c, current, y);
  double t = from;
  for (; knot < command.time_s.size() && command.time_s[knot] <= t0; ++knot) {
    RelaxCommandLags(layout, c, current, command.time_s[knot] - t, y);
    current = tracker.Next(command.value_V[knot]);
    t = command.time_s[knot];
  }
  RelaxCommandLags(layout, c, current, t0 - t, y);
}

// The lag states of y at t0: settled for the initial command, or replayed.
template <typename T>
void InitialLagStates(const ActuatorLayout& layout, const ActuatorCoefficients<T>& c,
                      const CommandSignal& command, const ValveCommandTracker& fresh,
                      const ValveCommand& initial_command, const InitialState& initial, double t0,
                      T* y) {
  if (std::isnan(initial.lag_history_from_s)) {
    SetLagStatesToEquilibrium(layout, c, initial_command, y);
  } else {
    ReplayLagHistory(layout, c, command, fresh, initial.lag_history_from_s, t0, y);
  }
}

SimulationSummary Failure(SimulationStatus status, std::string message) {
  SimulationSummary summary;
  summary.status = status;
  summary.message = std::move(message);
  return summary;
}

// Why this input cannot be simulated; empty when it can.
std::string CheckInputs(const Parameters& params, const CommandSignal& command,
                        const InitialState& initial, const std::vector<double>& output_times_s,
                        const SimulationOptions& options) {
  std::string error;
  if (!options.IsValid(&error)) return "options: " + error;
  if (!command.IsValid(&error)) return error;
  const auto problems = Validate(params);
  if (!problems.empty())
    return "parameters: " + problems.front().path + ": " + problems.front().message;
  for (const auto& [name, values] : params.effects) {
    if (!FindEffect(name)->simulated) return "effect " + name + " is not simulated yet";
  }
  if (output_times_s.empty()) return "no output times";
  for (size_t i = 0; i < output_times_s.size(); ++i) {
    if (!std::isfinite(output_times_s[i]) || (i > 0 && output_times_s[i] < output_times_s[i - 1])) {
      return "output times must be finite and non-decreasing";
    }
  }
  if (!(initial.p1_Pa > 0 && initial.p2_Pa > 0)) return "initial pressures must be > 0 Pa absolute";
  if (!std::isnan(initial.lag_history_from_s) &&
      !(initial.lag_history_from_s <= output_times_s.front())) {
    return "lag_history_from_s must not be after the first output time";
  }
  const double half_stroke = 0.5 * params.cylinder.stroke_m;
  if (!(std::fabs(initial.position_m) <= half_stroke) || !std::isfinite(initial.velocity_m_per_s)) {
    return "initial position must lie within the stroke, velocity finite";
  }
  return {};
}

void AppendSample(const ModelData& data, double t, double command_V, const double* y,
                  Trajectory* out) {
  double rate[kMaxStates];
  ActuatorOutputs<double> outputs;
  ActuatorDerivatives(data.layout, data.coefficients, data.command, data.motion, y, rate, &outputs);
  out->t_s.push_back(t);
  out->u_V.push_back(command_V);
  out->x_m.push_back(y[kPosition]);
  out->v_m_per_s.push_back(y[kVelocity]);
  const ChamberPressures<double> chambers = DecodeChambers(data.coefficients, y);
  out->p1_Pa.push_back(chambers.p1_Pa);
  out->p2_Pa.push_back(chambers.p2_Pa);
  out->q1_kg_per_s.push_back(outputs.q1_kg_per_s);
  out->q2_kg_per_s.push_back(outputs.q2_kg_per_s);
}

// The coefficients with dc/dp_j of each free parameter in derivative j, by
// central differences of the (algebraic) parameter -> coefficient map.
template <typename Jet>
ActuatorCoefficients<Jet> CoefficientsWithDerivatives(const Parameters& params,
                                                      const SensitivityOptions& sensitivity,
                                                      const ModelRegularization& regularization) {
  auto base = MakeActuatorCoefficients<double>(params, regularization);
  ActuatorCoefficients<Jet> result;
  Jet* out = CoefficientArray(&result);
  const double* value = CoefficientArray(&base);
  for (int k = 0; k < kCoefficientCount<double>; ++k) out[k] = Jet(value[k]);
  for (size_t j = 0; j < sensitivity.parameter_paths.size(); ++j) {
    const std::string& path = sensitivity.parameter_paths[j];
    double nominal = 0;
    GetParameter(params, path, &nominal);
    const double step = 1e-6 * sensitivity.parameter_scales[j];
    Parameters up = params, down = params;
    SetParameter(&up, path, nominal + step);
    SetParameter(&down, path, nominal - step);
    auto plus = MakeActuatorCoefficients<double>(up, regularization);
    auto minus = MakeActuatorCoefficients<double>(down, regularization);
    const double* p = CoefficientArray(&plus);
    const double* m = CoefficientArray(&minus);
    for (int k = 0; k < kCoefficientCount<double>; ++k) out[k].v[j] = (p[k] - m[k]) / (2 * step);
  }
  return result;
}

// ParameterJets with `Lanes` derivative lanes (at least the parameter count).
template <int Lanes>
class LanedJets final : public ParameterJets {
 public:
  using Jet = ceres::Jet<double, Lanes>;

  LanedJets(const Parameters& params, const SensitivityOptions& sensitivity,
            const ModelRegularization& regularization)
      : coefficients_(CoefficientsWithDerivatives<Jet>(params, sensitivity, regularization)),
        initial_p1_lane_(sensitivity.initial_pressures
                             ? static_cast<int>(sensitivity.parameter_paths.size())
                             : -1) {}

  int Rates(const ModelData& data, const double* y, const N_Vector* s,
            N_Vector* rates) const override {
    const int n = data.layout.size;
    Jet state[kMaxStates];
    Jet rate[kMaxStates];
    Load(data, y, s, state);
    ActuatorDerivatives(data.layout, coefficients_, data.command, data.motion, state, rate,
                        static_cast<ActuatorOutputs<Jet>*>(nullptr));
    for (int j = 0; j < data.parameter_count; ++j) {
      double* out = N_VGetArrayPointer(rates[j]);
      for (int i = 0; i < n; ++i) {
        out[i] = rate[i].v[j];
        if (!std::isfinite(out[i])) return 1;
      }
    }
    return 0;
  }

  void SwitchingDerivatives(const ModelData& data, const double* y, const N_Vector* s, int fired,
                            double* dg_dp) const override {
    Jet carried[kMaxStates];
    Load(data, y, s, carried);
    Jet g[2];
    SwitchingValues(data, coefficients_, carried, g);
    for (int j = 0; j < data.parameter_count; ++j) dg_dp[j] = g[fired].v[j];
  }

  void AppendOutputs(const ModelData& data, const double* y, const N_Vector* s, Eigen::Index row,
                     TrajectorySensitivities* out) const override {
    Jet state[kMaxStates];
    Jet rate[kMaxStates];
    Load(data, y, s, state);
    ActuatorOutputs<Jet> outputs;
    ActuatorDerivatives(data.layout, coefficients_, data.command, data.motion, state, rate,
                        &outputs);
    const ChamberPressures<Jet> chambers = DecodeChambers(coefficients_, state);
    for (int j = 0; j < data.parameter_count; ++j) {
      out->x(row, j) = state[kPosition].v[j];
      out->p1(row, j) = chambers.p1_Pa.v[j];
      out->p2(row, j) = chambers.p2_Pa.v[j];
      out->q1(row, j) = outputs.q1_kg_per_s.v[j];
      out->q2(row, j) = outputs.q2_kg_per_s.v[j];
    }
  }

  std::vector<std::vector<double>> Initial(const ModelData& data, const InitialState& initial,
                                           const CommandSignal& command,
                                           const ValveCommandTracker& fresh,
                                           const ValveCommand& initial_command,
                                           double t0) const override {
    Jet y[kMaxStates];
    for (auto& value : y) value = Jet(0.0);
    y[kPosition] = Jet(initial.position_m);
    y[kVelocity] = Jet(data.motion == MotionMode::kStuck ? 0.0 : initial.velocity_m_per_s);
    const bool seeded = initial_p1_lane_ >= 0;  // the initial pressures' own lanes
    SetChamberPressures(coefficients_,
                        seeded ? Jet(initial.p1_Pa, initial_p1_lane_) : Jet(initial.p1_Pa),
                        seeded ? Jet(initial.p2_Pa, initial_p1_lane_ + 1) : Jet(initial.p2_Pa), y);
    InitialLagStates(data.layout, coefficients_, command, fresh, initial_command, initial, t0, y);
    std::vector<std::vector<double>> s(static_cast<size_t>(data.parameter_count),
                                       std::vector<double>(static_cast<size_t>(data.layout.size)));
    for (int j = 0; j < data.parameter_count; ++j) {
      for (int i = 0; i < data.layout.size; ++i) s[j][i] = y[i].v[j];
    }
    return s;
  }

 private:
  // The state as Jets whose derivative j is the sensitivity s_j = dy/dp_j.
  static void Load(const ModelData& data, const double* y, const N_Vector* s, Jet* jets) {
    for (int i = 0; i < data.layout.size; ++i) {
      jets[i] = Jet(y[i]);
      for (int j = 0; j < data.parameter_count; ++j) jets[i].v[j] = N_VGetArrayPointer(s[j])[i];
    }
  }

  ActuatorCoefficients<Jet> coefficients_;
  int initial_p1_lane_;  // p2's follows; -1 without initial-pressure lanes
};

// The fewest lanes of those compiled that hold every free parameter.
std::unique_ptr<const ParameterJets> MakeParameterJets(const Parameters& params,
                                                       const SensitivityOptions& sensitivity,
                                                       const ModelRegularization& regularization) {
  static_assert(kMaxSensitivityParameters == 16, "compile a LanedJets for the new maximum");
  const int count = sensitivity.Columns();
  if (count <= 2) return std::make_unique<LanedJets<2>>(params, sensitivity, regularization);
  if (count <= 4) return std::make_unique<LanedJets<4>>(params, sensitivity, regularization);
  if (count <= 10) return std::make_unique<LanedJets<10>>(params, sensitivity, regularization);
  if (count <= 12) return std::make_unique<LanedJets<12>>(params, sensitivity, regularization);
  return std::make_unique<LanedJets<16>>(params, sensitivity, regularization);
}

// The run itself, once inputs are known to be valid. `sensitivity` and
// `derivatives` are both null (plain run) or both set.
SimulationSummary Run(const Parameters& params, const CommandSignal& command,
                      const InitialState& initial, const std::vector<double>& times,
                      const SimulationOptions& options, const SensitivityOptions* sensitivity,
                      Trajectory* out, TrajectorySensitivities* derivatives) {
  ModelData data;
  data.layout = ActuatorLayout::For(params);
  data.coefficients = MakeActuatorCoefficients<double>(params, options.regularization);
  data.jet_coefficients = MakeActuatorCoefficients<JetN>(params, options.regularization);

  const double t0 = times.front();
  const ValveCommandTracker fresh(params.valve.branch, options.hysteresis_threshold_V);
  ValveCommandTracker tracker = fresh;
  data.command = tracker.Next(command.initial_V);
  data.supply_pressure_Pa = params.supply.supply_pressure_Pa;
  double y0[kMaxStates] = {initial.position_m, initial.velocity_m_per_s};
  SetChamberPressures(data.coefficients, initial.p1_Pa, initial.p2_Pa, y0);
  InitialLagStates(data.layout, data.coefficients, command, fresh, data.command, initial, t0, y0);
  data.breakaway_margin_N = options.breakaway_margin_N;
  data.reversal_velocity_m_per_s = options.velocity_tolerance_m_per_s;
  data.motion = options.stick_slip == StickSlipTreatment::kEvents ? InitialMode(data, y0)
                                                                  : MotionMode::kRegularized;
  if (data.motion == MotionMode::kStuck) y0[kVelocity] = 0.0;

  // Taken where y0 is: before the knots at t0 change the command.
  std::vector<std::vector<double>> initial_sensitivities;
  if (sensitivity != nullptr) {
    data.parameter_count = sensitivity->Columns();
    data.parameter_jets = MakeParameterJets(params, *sensitivity, options.regularization);
    initial_sensitivities =
        data.parameter_jets->Initial(data, initial, command, fresh, data.command, t0);
  }

  // Knots at or before t0 have already happened: apply them in order.
  size_t next_knot = 0;
  double current_V = command.initial_V;
  while (next_knot < command.time_s.size() && command.time_s[next_knot] <= t0) {
    current_V = command.value_V[next_knot++];
    data.command = tracker.Next(current_V);
  }

  Integrator integrator(&data, options, t0, y0);
  if (sensitivity != nullptr) {
    // The initial pressures' typical magnitude: their own values.
    std::vector<double> scales = sensitivity->parameter_scales;
    if (sensitivity->initial_pressures) scales.insert(scales.end(), {initial.p1_Pa, initial.p2_Pa});
    integrator.EnableSensitivities(initial_sensitivities, *sensitivity, scales);
    for (Eigen::MatrixXd* m : {&derivatives->x, &derivatives->p1, &derivatives->p2,
                               &derivatives->q1, &derivatives->q2}) {
      m->setZero(static_cast<Eigen::Index>(times.size()), data.parameter_count);
    }
  }
  double t = t0;
  const double t_end = times.back();
  *out = Trajectory{};
  SimulationSummary summary;
  const auto fail = [&](const char* what) {
    summary = integrator.Counters();
    summary.status = SimulationStatus::kSolverFailure;
    std::ostringstream message;
    message << what << " at t = " << t << " s";
    if (!data.last_solver_message.empty()) message << " (" << data.last_solver_message << ")";
    summary.message = message.str();
    return summary;
  };
  for (const double t_out : times) {
    while (next_knot < command.time_s.size() && command.time_s[next_knot] <= t_out) {
      const double knot = command.time_s[next_knot];
      if (knot > t + 1e-12 * std::fmax(1.0, std::fabs(t)) && integrator.AdvanceTo(knot, knot) < 0) {
        return fail("integration failed");
      }
      t = knot;
      const double new_V = command.value_V[next_knot++];
      const ValveCommand previous = data.command;
      data.command = tracker.Next(new_V);
      const bool branch_switched = previous.decreasing_branch != data.command.decreasing_branch;
      if (std::fabs(new_V - current_V) > options.restart_jump_V || branch_switched) {
        if (integrator.Restart(t) < 0) return fail("restart failed");
      }
      current_V = new_V;
    }
    // An output a few ulps after the current time needs no step (and CVODE
    // refuses one that short).
    if (t_out > t + 1e-12 * std::fmax(1.0, std::fabs(t))) {
      const double stop =
          next_knot < command.time_s.size() ? std::fmin(command.time_s[next_knot], t_end) : t_end;
      if (integrator.AdvanceTo(t_out, stop) < 0) return fail("integration failed");
      t = t_out;
    }
    if (integrator.Counters().steps > options.max_steps) return fail("step budget exhausted");
    if (integrator.events() > options.max_events) return fail("stick/slip event budget exhausted");
    if (sensitivity != nullptr) {
      const N_Vector* s = integrator.Sensitivities();
      if (s == nullptr) return fail("sensitivities unavailable");
      data.parameter_jets->AppendOutputs(data, integrator.state(), s,
                                         static_cast<Eigen::Index>(out->size()), derivatives);
    }
    AppendSample(data, t_out, current_V, integrator.state(), out);
  }
  summary = integrator.Counters();
  return summary;
}

}  // namespace

bool SimulationOptions::IsValid(std::string* error) const {
  const auto fail = [error](const char* what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (!(relative_tolerance > 0 && relative_tolerance < 1)) {
    return fail("relative_tolerance must be in (0, 1)");
  }
  if (!(position_tolerance_m > 0 && velocity_tolerance_m_per_s > 0 && pressure_tolerance_Pa > 0 &&
        mass_flow_tolerance_kg_per_s > 0 && opening_tolerance_V > 0)) {
    return fail("absolute tolerances must be > 0");
  }
  if (max_steps <= 0) return fail("max_steps must be > 0");
  if (!(hysteresis_threshold_V > 0 && hysteresis_threshold_V < 1)) {
    return fail("hysteresis_threshold_V must be in (0, 1)");
  }
  if (!(restart_jump_V >= 0)) return fail("restart_jump_V must be >= 0");
  if (!(breakaway_margin_N >= 0)) return fail("breakaway_margin_N must be >= 0");
  if (max_events <= 0) return fail("max_events must be > 0");
  return regularization.IsValid(error);
}

InitialState RetractedAtRest(const Parameters& params) {
  InitialState state;
  state.position_m = -0.5 * params.cylinder.stroke_m;
  state.p1_Pa = params.supply.atmospheric_pressure_Pa;
  state.p2_Pa = params.supply.atmospheric_pressure_Pa;
  return state;
}

std::string SimulationSummary::BriefReport() const {
  std::ostringstream out;
  static const char* kStatus[] = {"success", "invalid input", "solver failure"};
  out << "Simulation: " << kStatus[static_cast<int>(status)];
  if (!message.empty()) out << " (" << message << ")";
  out << ", " << simulated_time_s << " s simulated in " << wall_time_s * 1e3 << " ms; " << steps
      << " steps, " << rhs_evaluations << " rhs, " << jacobian_evaluations << " Jacobians, "
      << error_test_failures << " error-test and " << convergence_failures
      << " convergence failures, " << restarts << " restarts, " << events << " stick/slip events";
  return out.str();
}

namespace {

SimulationSummary SimulateTimed(const Parameters& params, const CommandSignal& command,
                                const InitialState& initial,
                                const std::vector<double>& output_times_s,
                                const SimulationOptions& options,
                                const SensitivityOptions* sensitivity, Trajectory* out,
                                TrajectorySensitivities* derivatives) {
  const auto start = std::chrono::steady_clock::now();
  SimulationSummary summary;
  std::string problem = CheckInputs(params, command, initial, output_times_s, options);
  if (problem.empty() && sensitivity != nullptr) {
    if (!sensitivity->IsValid(params, &problem)) problem = "sensitivities: " + problem;
  }
  if (!problem.empty()) {
    summary = Failure(SimulationStatus::kInvalidInput, problem);
  } else {
    try {
      summary =
          Run(params, command, initial, output_times_s, options, sensitivity, out, derivatives);
    } catch (const internal::SundialsSetupError& error) {
      summary = Failure(SimulationStatus::kSolverFailure, error.what());
    }
    summary.simulated_time_s = out->size() ? out->t_s.back() - output_times_s.front() : 0.0;
  }
  summary.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace

SimulationSummary Simulate(const Parameters& params, const CommandSignal& command,
                           const InitialState& initial, const std::vector<double>& output_times_s,
                           const SimulationOptions& options, Trajectory* out) {
  return SimulateTimed(params, command, initial, output_times_s, options, nullptr, out, nullptr);
}

SimulationSummary SimulateWithSensitivities(const Parameters& params, const CommandSignal& command,
                                            const InitialState& initial,
                                            const std::vector<double>& output_times_s,
                                            const SimulationOptions& options,
                                            const SensitivityOptions& sensitivity, Trajectory* out,
                                            TrajectorySensitivities* derivatives) {
  return SimulateTimed(params, command, initial, output_times_s, options, &sensitivity, out,
                       derivatives);
}

bool SensitivityOptions::IsValid(const Parameters& params, std::string* error) const {
  const auto fail = [error](const std::string& what) {
    if (error != nullptr) *error = what;
    return false;
  };
  if (Columns() == 0) return fail("no free parameters");
  if (Columns() > kMaxSensitivityParameters) {
    return fail("at most " + std::to_string(kMaxSensitivityParameters) +
                " sensitivities (free parameters and initial pressures)");
  }
  if (parameter_scales.size() != parameter_paths.size()) {
    return fail("one scale per free parameter expected");
  }
  for (size_t j = 0; j < parameter_paths.size(); ++j) {
    double value = 0;
    if (!GetParameter(params, parameter_paths[j], &value)) {
      return fail("no parameter " + parameter_paths[j] + " in this parameter set");
    }
    if (!(parameter_scales[j] > 0 && std::isfinite(parameter_scales[j]))) {
      return fail("the scale of " + parameter_paths[j] + " must be > 0");
    }
  }
  return true;
}

std::vector<double> UniformTimes(double t0_s, double t_end_s, double rate_Hz) {
  std::vector<double> times;
  const long count = static_cast<long>(std::floor((t_end_s - t0_s) * rate_Hz + 1e-9)) + 1;
  times.reserve(static_cast<size_t>(std::max(count, 0L)));
  for (long i = 0; i < count; ++i) times.push_back(t0_s + static_cast<double>(i) / rate_Hz);
  return times;
}

}  // namespace pneumaid
