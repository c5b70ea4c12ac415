// Forward simulation of the actuator with SUNDIALS CVODES (BDF, Newton with a
// dense, exact Jacobian from automatic differentiation of the model).
#pragma once

#include <atomic>
#include <limits>
#include <string>
#include <vector>

#include "pneumaid/model/actuator.h"
#include "pneumaid/model/parameters.h"
#include "pneumaid/sim/command.h"
#include "pneumaid/trajectory.h"

namespace pneumaid {

// How static friction is simulated.
enum class StickSlipTreatment {
  // Exact Eq. 12 switching: the rod is held (x, v frozen) until the driving
  // force exceeds Fs, slides with the Stribeck law of its direction, and sticks
  // again when v returns to zero with the force below Fs. CVODE root finding
  // locates each switch; the integrator restarts there. A parameter set with
  // the stick_creep effect is simulated as kRegularized (its rod creeps).
  kEvents,
  // One smooth law (ModelRegularization::stick_velocity_m_per_s, or the
  // stick_creep effect's v): no events, creep below the stick velocity while
  // held. For smooth sensitivities.
  kRegularized,
};

struct SimulationOptions {
  // Relative tolerance of every state.
  double relative_tolerance = 1e-6;
  // Absolute tolerances per kind of state.
  double position_tolerance_m = 1e-9;
  double velocity_tolerance_m_per_s = 1e-7;
  double pressure_tolerance_Pa = 1.0;
  // Lagged conductances and flows, and measured flows (q_max is about 1e-4).
  double mass_flow_tolerance_kg_per_s = 1e-11;
  // Lagged valve openings (valve_lag effect).
  double opening_tolerance_V = 1e-7;
  // Chamber gas temperatures (heat_transfer effect).
  double temperature_tolerance_K = 1e-4;
  // Work bound: the run fails (never hangs) past this many solver steps.
  long max_steps = 5'000'000;
  // Error-test failures CVODE allows on one step before it gives up. Each
  // failure past the third lowers the order by one: CVODE's default of 7
  // could end a run where a light rod creeps off a stop under the smooth
  // stick law, whose stiffness ends at |v| = the stick velocity (its
  // saturation is C1 only) before the order had come down to 1.
  int max_error_test_failures = 20;
  // Cooperative stop (a batch unit's time limit): when set and true, the run
  // fails at its next output sample with "stopped". Not owned.
  const std::atomic<bool>* stop = nullptr;
  // Hysteresis mode: change of a valve opening that re-latches its branch.
  double hysteresis_threshold_V = 0.01;
  // A command change at a knot larger than this (or a branch switch) restarts
  // the integrator at low order; smaller changes (sampled, noisy commands) are
  // left to the step-size control, which is much cheaper at 1 kHz.
  double restart_jump_V = 0.02;
  // How sticking is simulated (events by default).
  StickSlipTreatment stick_slip = StickSlipTreatment::kEvents;
  // Switching hysteresis [N]: a stuck rod breaks away only once the driving
  // force exceeds Fs by this much, so a force resting at Fs cannot chatter.
  double breakaway_margin_N = 1e-6;
  // Work bound on stick/slip switches; the run fails past it.
  long max_events = 100'000;
  // Numerical treatment of stick (regularized mode), end stops and the orifice.
  ModelRegularization regularization;
  // Record what the run reads of each direction's friction
  // (SimulationSummary::friction_use; FrictionUse::Everything without). Off
  // by default: the stuck phases' root function then notes nothing.
  bool record_friction_use = false;

  bool IsValid(std::string* error) const;
};

struct InitialState {
  double position_m = 0.0;  // from mid-stroke
  double velocity_m_per_s = 0.0;
  double p1_Pa = 1e5;
  double p2_Pa = 1e5;
  // NaN: the lag states start settled for the command's initial value. A
  // time before the first output time: they start settled for the command at
  // that time and follow the command (zero-order hold) to the first output
  // time, as they would have on the rig (a run restarted mid-log from a logged
  // state). Replayed exactly: the lags driven by the command alone (valve_lag,
  // the conductance lag, each exact on its own); the flow lags start settled.
  double lag_history_from_s = std::numeric_limits<double>::quiet_NaN();
};

// The paper's start: rod at the retracted end, at rest, both chambers at p_atm.
InitialState RetractedAtRest(const Parameters& params);

enum class SimulationStatus { kSuccess, kInvalidInput, kSolverFailure };

// What a run's trajectory read of each direction's friction coefficients
// (side 0: positive, 1: negative), recorded by Simulate as it goes when
// SimulationOptions::record_friction_use asks (not by
// the sensitivity runs' event jumps, which do not steer the trajectory). A
// direction the rod never slid in (nor ran regularised) is read only by its
// breakaway tests (stuck, and coming to rest), each comparing its static
// force with the driving force. Such a test keeps its outcome for any static
// force above the largest force the tests saw, and a switching function that
// keeps its sign is all CVODES' root finding reads of it: the same run with
// that direction's coefficients changed, its Fs and the run's own above that
// force, follows the same trajectory to the bit (Unaffected).
struct FrictionUse {
  bool slid[2] = {false, false};
  // The largest force [N] a breakaway test of the side asked its static
  // force to hold: the driving force (along the side) less the margin, over
  // the friction's pressure scale; -inf when never tested.
  double breakaway_needed_N[2] = {-std::numeric_limits<double>::infinity(),
                                  -std::numeric_limits<double>::infinity()};

  // Every coefficient read: what a run that failed, or was not recorded, says.
  static FrictionUse Everything() {
    FrictionUse use;
    use.slid[0] = use.slid[1] = true;
    return use;
  }
  void NoteSliding(int side) { slid[side] = true; }
  void NoteBreakawayTest(int side, double needed_N);
  // Whether a static force of `static_force_N` on the side holds every
  // breakaway test the run made there, by a margin the round-off keeps, and
  // the run never slid that way: with both its own and another set's Fs
  // unaffected, the other set's run (that side's coefficients alone changed)
  // is this one to the bit.
  bool Unaffected(int side, double static_force_N) const;
};

struct SimulationSummary {
  SimulationStatus status = SimulationStatus::kSuccess;
  std::string message;  // why it failed; empty on success
  long steps = 0;
  long rhs_evaluations = 0;
  long jacobian_evaluations = 0;
  long error_test_failures = 0;
  long convergence_failures = 0;
  long restarts = 0;
  long events = 0;  // stick/slip switches
  double simulated_time_s = 0.0;
  double wall_time_s = 0.0;
  FrictionUse friction_use = FrictionUse::Everything();  // recorded by a successful run on request

  bool ok() const { return status == SimulationStatus::kSuccess; }
  std::string BriefReport() const;
};

// Simulates from `initial` at output_times_s[0] to the last output time and
// fills `out` with t, u, x, v, p1, p2, q1, q2 at every output time (which must
// be non-decreasing). Lag states start settled for command.initial_V. Never
// throws for numerical trouble: the summary says what went wrong.
SimulationSummary Simulate(const Parameters& params, const CommandSignal& command,
                           const InitialState& initial, const std::vector<double>& output_times_s,
                           const SimulationOptions& options, Trajectory* out);

// Uniform output times from t0 to t_end inclusive at `rate_Hz`.
std::vector<double> UniformTimes(double t0_s, double t_end_s, double rate_Hz);

}  // namespace pneumaid
