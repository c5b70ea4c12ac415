#include "pneumaid/sim/simulate.h"

#include <ceres/jet.h>

#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>

#include "cvode_handles.h"
#include "fast_kernels.h"
#include "lag_history.h"
#include "model_data.h"
#include "parameter_jets.h"
#include "pneumaid/model/effects.h"
#include "pneumaid/model/parameter_table.h"
#include "pneumaid/sim/sensitivities.h"

namespace pneumaid {
namespace {

using namespace internal;  // model_data.h, lag_history.h, parameter_jets.h

// CVODES sensitivity right-hand side callback. Never throws.
int SensitivityRightHandSide(int, sunrealtype, N_Vector y, N_Vector, N_Vector* sensitivities,
                             N_Vector* rates, void* user_data, N_Vector, N_Vector) {
  const auto* data = static_cast<const ModelData*>(user_data);
  return data->parameter_jets->Rates(*data, N_VGetArrayPointer(y), sensitivities, rates);
}

// CVODE right-hand side. Returns 1 (recoverable: CVODE retries with a smaller
// step) on a non-finite rate; never throws. (Pressures are positive by
// construction of the chamber state.)
PNEUMAID_FLATTEN int RightHandSide(sunrealtype, N_Vector y, N_Vector ydot, void* user_data) {
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
PNEUMAID_FLATTEN int Jacobian(sunrealtype, N_Vector y, N_Vector, SUNMatrix jacobian,
                              void* user_data, N_Vector, N_Vector, N_Vector) {
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

// CVODE root function. Never throws.
PNEUMAID_FLATTEN int SwitchingFunctions(sunrealtype, N_Vector y, sunrealtype* g, void* user_data) {
  const auto* data = static_cast<const ModelData*>(user_data);
  SwitchingValues(*data, data->coefficients, N_VGetArrayPointer(y), g);
  return 0;
}

// The same, noting the breakaway tests in data->friction_use
// (SimulationOptions::record_friction_use). Never throws.
PNEUMAID_FLATTEN int RecordedSwitchingFunctions(sunrealtype, N_Vector y, sunrealtype* g,
                                                void* user_data) {
  auto* data = static_cast<ModelData*>(user_data);
  SwitchingValues(*data, data->coefficients, N_VGetArrayPointer(y), g, &data->friction_use);
  return 0;
}

// The motion mode for a rod at rest at state y: held by static friction
// unless the driving force exceeds the breakaway force (plus the margin), and
// held by an end stop it is pushed against. The tests are noted in
// data->friction_use.
MotionMode ModeAtRest(ModelData* mutable_data, const double* y) {
  const ModelData& data = *mutable_data;
  const auto& c = data.coefficients;
  const ChamberPressures<double> p = DecodeChambers(c, y);
  const double force = DrivingForce(c, y, p);
  NoteBreakawayTests(data, force, FrictionScale(c, p), y[kPosition], &mutable_data->friction_use);
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

MotionMode InitialMode(ModelData* data, const double* y) {
  if (y[kVelocity] > 0) return MotionMode::kSlidingPositive;
  if (y[kVelocity] < 0) return MotionMode::kSlidingNegative;
  return ModeAtRest(data, y);
}

// Sets the motion mode and notes the friction it reads (FrictionUse).
void SetMotion(ModelData* data, MotionMode motion) {
  data->motion = motion;
  if (motion == MotionMode::kSlidingPositive || motion == MotionMode::kRegularized)
    data->friction_use.NoteSliding(0);
  if (motion == MotionMode::kSlidingNegative || motion == MotionMode::kRegularized)
    data->friction_use.NoteSliding(1);
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
    CheckFlag(CVodeSetMaxErrTestFails(mem, options.max_error_test_failures),
              "CVodeSetMaxErrTestFails");
    if (data_->motion != MotionMode::kRegularized) {
      CheckFlag(CVodeRootInit(
                    mem, 2,
                    options.record_friction_use ? RecordedSwitchingFunctions : SwitchingFunctions),
                "CVodeRootInit");
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

  // Steps taken so far, restarts included (what Counters() says, cheaply:
  // it is asked at every output).
  long steps() const {
    long value = 0;
    CVodeGetNumSteps(memory_.get(), &value);
    return banked_.steps + value;
  }

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
      SetMotion(data_, fired == 0 ? MotionMode::kSlidingPositive : MotionMode::kSlidingNegative);
    } else {
      if (fired == 1) {
        const double half_stroke = data_->coefficients.end_stop.half_stroke_m;
        y[kPosition] = data_->motion == MotionMode::kSlidingPositive ? half_stroke : -half_stroke;
        jump.reset_position = true;
      }
      y[kVelocity] = 0.0;
      jump.reset_velocity = true;
      SetMotion(data_, ModeAtRest(data_, y));
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
    total.steps = steps();
    long value = 0;
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
    // One state per valve pair (kValveCount here wrote past the state vector
    // when the valve lag was its last group, and over the tube's otherwise).
    for (int i = 0; i < kValvePairCount && layout.valve_lag; ++i)
      atol[layout.opening_begin + i] = options.opening_tolerance_V;
    for (int i = 0; i < 2 && layout.heat_transfer; ++i)
      atol[layout.temperature_begin + i] = options.temperature_tolerance_K;
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
  out->p1_Pa.push_back(outputs.p1_Pa);
  out->p2_Pa.push_back(outputs.p2_Pa);
  out->q1_kg_per_s.push_back(outputs.q1_kg_per_s);
  out->q2_kg_per_s.push_back(outputs.q2_kg_per_s);
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
  // A rod that creeps (stick_creep) has no stuck mode to switch to.
  const bool events = options.stick_slip == StickSlipTreatment::kEvents && !Creeps(params);
  SetMotion(&data, events ? InitialMode(&data, y0) : MotionMode::kRegularized);
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
  for (std::vector<double>* column : {&out->t_s, &out->u_V, &out->x_m, &out->v_m_per_s, &out->p1_Pa,
                                      &out->p2_Pa, &out->q1_kg_per_s, &out->q2_kg_per_s}) {
    column->reserve(times.size());
  }
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
    if (integrator.steps() > options.max_steps) return fail("step budget exhausted");
    if (options.stop != nullptr && options.stop->load(std::memory_order_relaxed))
      return fail("stopped (the caller's time limit)");
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
  if (options.record_friction_use) summary.friction_use = data.friction_use;
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
        mass_flow_tolerance_kg_per_s > 0 && opening_tolerance_V > 0 &&
        temperature_tolerance_K > 0)) {
    return fail("absolute tolerances must be > 0");
  }
  if (max_steps <= 0) return fail("max_steps must be > 0");
  if (max_error_test_failures < 1) return fail("max_error_test_failures must be >= 1");
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

void FrictionUse::NoteBreakawayTest(int side, double needed_N) {
  breakaway_needed_N[side] = std::fmax(breakaway_needed_N[side], needed_N);
}

bool FrictionUse::Unaffected(int side, double static_force_N) const {
  if (slid[side]) return false;
  const double needed = breakaway_needed_N[side];
  if (needed == -std::numeric_limits<double>::infinity()) return true;  // never tested
  // Above by a relative 1e-9: the switching function, computed otherwise
  // than `needed`, keeps its sign through the round-off.
  return static_force_N > needed + 1e-9 * std::fabs(needed) + 1e-12;
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
