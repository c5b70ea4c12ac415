#include "parameter_jets.h"

#include <cmath>

#include "pneumaid/model/parameter_table.h"

namespace pneumaid::internal {
namespace {

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

  PNEUMAID_FLATTEN int Rates(const ModelData& data, const double* y, const N_Vector* s,
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

  PNEUMAID_FLATTEN void AppendOutputs(const ModelData& data, const double* y, const N_Vector* s,
                                      Eigen::Index row,
                                      TrajectorySensitivities* out) const override {
    Jet state[kMaxStates];
    Jet rate[kMaxStates];
    Load(data, y, s, state);
    ActuatorOutputs<Jet> outputs;
    ActuatorDerivatives(data.layout, coefficients_, data.command, data.motion, state, rate,
                        &outputs);
    for (int j = 0; j < data.parameter_count; ++j) {
      out->x(row, j) = state[kPosition].v[j];
      out->p1(row, j) = outputs.p1_Pa.v[j];
      out->p2(row, j) = outputs.p2_Pa.v[j];
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

}  // namespace

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

}  // namespace pneumaid::internal
