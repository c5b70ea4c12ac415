// The params-v1 parameter set as plain structs, SI units, pressures absolute.
//
// Field names carry their unit. Default values are the seed paper's (Section 3,
// Table 2, Table 3 vertical), so `Parameters{}` is `configs/paper.yaml`.
#pragma once

#include <map>
#include <string>
#include <vector>

namespace pneumaid {

struct GasParams {
  double heat_capacity_ratio = 1.4;       // k [-]
  double gas_constant_J_per_kgK = 287.0;  // R [J/(kg K)]
  double temperature_K = 293.0;           // T [K], supply and chamber gas
};

struct SupplyParams {
  double supply_pressure_Pa = 5.0e5;       // absolute
  double atmospheric_pressure_Pa = 1.0e5;  // absolute, also the exhaust
};

enum class Orientation { kVertical, kHorizontal };

struct CylinderParams {
  double area_1_m2 = 2.01e-4;  // cap side piston area (chamber 1)
  double area_2_m2 = 1.73e-4;  // rod side annulus area (chamber 2)
  double stroke_m = 0.05;      // L; x runs from -L/2 to +L/2
  double dead_volume_1_m3 = 1.01e-7;
  double dead_volume_2_m3 = 8.65e-8;
  double load_mass_kg = 0.15;  // M: load + piston + rod
  // Vertical: gravity acts along -x (the rod lifts the load when extending).
  Orientation orientation = Orientation::kVertical;
};

// One branch of K_vp(u), seed paper Eq. 3:
//   K_vp = q_max (a u^4 + b u^3 + c u^2 + d u) for u < u_sat, q_max above,
// clamped at zero.
struct KvpBranchParams {
  double a = 0, b = 0, c = 0, d = 0;  // polynomial coefficients [-]
  double q_max_kg_per_s = 0;          // choked mass flow at supply pressure, full opening
  double u_sat_V = 0.75;              // opening above which K_vp = q_max
};

enum class ValveBranchMode { kIncreasing, kDecreasing, kHysteresis };

struct ValveParams {
  // N in Eq. 4, kept as given (1181 in the paper, = C1 p_supply / sqrt(T)).
  double normalization = 1181.0;
  KvpBranchParams increasing{10.93, -18.95, 8.52, 1.00, 9.25e-5, 0.75};
  KvpBranchParams decreasing{9.86, -19.30, 10.95, -0.21, 9.15e-5, 0.75};
  ValveBranchMode branch = ValveBranchMode::kIncreasing;
};

enum class PipelineModel {
  kConductanceLag,  // Eq. 5 lag acting on each valve's conductance (mass-conserving)
  kFlowLag,         // Eq. 5 literally, on the mass flow (paper reproduction only)
  kNone,            // no tube dynamics
};

struct DeltaAtLength {
  double tube_length_m = 0;
  double delta_per_s = 0;
};

struct PipelineParams {
  PipelineModel model = PipelineModel::kConductanceLag;
  // Eq. 5 rate constant. The paper says the flow takes "almost 0.5 s" to reach
  // its maximum; reading "almost" as 98 % gives delta = -ln(0.02)/0.5 = 7.8 ~ 8.0.
  double delta_per_s = 8.0;
  double tube_length_m = 0.38;
  std::vector<DeltaAtLength> delta_by_length;  // what identify measured, optional
};

// Eq. 12 for one direction of motion, all magnitudes.
struct StribeckParams {
  double static_force_N = 10.0;             // Fs
  double dynamic_force_N = 0.5;             // Fd
  double viscous_N_s_per_m = 5.0;           // b
  double stribeck_velocity_m_per_s = 0.01;  // vs
};

struct FrictionParams {
  StribeckParams positive{10.0, 0.5, 5.0, 0.01};  // v > 0 (extending)
  StribeckParams negative{10.0, 5.0, 5.0, 0.01};  // v < 0 (retracting)
};

// Effects added to the base model: effect name -> {parameter name -> value}.
// Names and parameters come from the catalog in effects.h.
using EffectSet = std::map<std::string, std::map<std::string, double>>;

struct Parameters {
  std::string unit = "paper";
  GasParams gas;
  SupplyParams supply;
  CylinderParams cylinder;
  ValveParams valve;
  PipelineParams pipeline;
  FrictionParams friction;
  EffectSet effects;
  std::map<std::string, double> uncertainty;  // parameter path -> standard error
  std::string provenance_yaml = "{}";         // free-form mapping, kept verbatim as YAML
};

// One thing wrong with a parameter set, addressed by its dotted path.
struct ParameterProblem {
  std::string path;
  std::string message;
};

// Physical consistency checks (ranges of every scalar, cross-field rules,
// effects against the catalog). Empty when the set is usable.
std::vector<ParameterProblem> Validate(const Parameters& params);

const char* ToString(Orientation value);
const char* ToString(ValveBranchMode value);
const char* ToString(PipelineModel value);

}  // namespace pneumaid
