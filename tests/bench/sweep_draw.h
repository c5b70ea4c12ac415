// The robustness sweep's units (issue 12, point 7): truth, protocol and
// model mismatch of unit `index` of a seeded sweep, drawn as issue 12 says.
// Shared by the sweep (robustness_sweep.cpp) and the tests that take one of
// its units as their case (each unit's draw depends on the seed and its
// index alone).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "pneumaid/ident/valve_fit.h"
#include "pneumaid/io/params_yaml.h"
#include "pneumaid/io/protocol.h"
#include "pneumaid/model/parameters.h"

#ifndef PNEUMAID_SOURCE_DIR
#error \
    "sweep_draw.h reads configs/ under PNEUMAID_SOURCE_DIR: define it (the tests' and benchmarks' CMake do)"
#endif

namespace pneumaid::sweep {

struct Draw {
  Parameters truth;
  Protocol protocol;
  double staircase_step_V = 0.05;  // or, for a valve ramp, the valve fit's node spacing
  std::string summary;             // what was drawn, one line
};

inline double Uniform(std::mt19937_64* rng, double low, double high) {
  return std::uniform_real_distribution<double>(low, high)(*rng);
}
inline double LogUniform(std::mt19937_64* rng, double low, double high) {
  return std::exp(Uniform(rng, std::log(low), std::log(high)));
}
template <typename T>
T Pick(std::mt19937_64* rng, const std::vector<T>& options) {
  return options[std::uniform_int_distribution<std::size_t>(0, options.size() - 1)(*rng)];
}

// Both directions' friction, one line: +(Fs Fd b vs[mm/s]) -(...).
inline std::string FrictionLine(const FrictionParams& f) {
  char line[160];
  std::snprintf(line, sizeof(line), "+(%.1f %.2f %.1f %.1f) -(%.1f %.2f %.1f %.1f)",
                f.positive.static_force_N, f.positive.dynamic_force_N, f.positive.viscous_N_s_per_m,
                f.positive.stribeck_velocity_m_per_s * 1e3, f.negative.static_force_N,
                f.negative.dynamic_force_N, f.negative.viscous_N_s_per_m,
                f.negative.stribeck_velocity_m_per_s * 1e3);
  return line;
}

// Truth, protocol and mismatch of unit `index`, drawn as issue 12 says.
inline Draw MakeDraw(std::uint64_t seed, int index) {
  std::mt19937_64 rng(seed * 1000003ULL + static_cast<std::uint64_t>(index));
  Draw d;
  Parameters& t = d.truth;
  t = LoadParams(std::string(PNEUMAID_SOURCE_DIR) + "/configs/paper.yaml");
  t.cylinder.orientation =
      Uniform(&rng, 0, 1) < 0.5 ? Orientation::kHorizontal : Orientation::kVertical;
  t.cylinder.load_mass_kg = LogUniform(&rng, 0.05, 1.5);
  const double q_scale = Uniform(&rng, 0.85, 1.15), u_sat = Uniform(&rng, 0.60, 0.85);
  for (KvpBranchParams* b : {&t.valve.increasing, &t.valve.decreasing}) {
    b->q_max_kg_per_s *= q_scale;
    b->u_sat_V = u_sat;
  }
  t.pipeline.delta_per_s = LogUniform(&rng, 3, 20);
  for (StribeckParams* f : {&t.friction.positive, &t.friction.negative}) {
    f->static_force_N = Uniform(&rng, 2, 20);
    f->dynamic_force_N = LogUniform(&rng, 0.1, std::min(10.0, 0.9 * f->static_force_N));
    f->viscous_N_s_per_m = Uniform(&rng, 1, 15);
    f->stribeck_velocity_m_per_s = LogUniform(&rng, 2e-3, 25e-3);
  }
  Protocol& p = d.protocol;
  p = LoadProtocol(std::string(PNEUMAID_SOURCE_DIR) + "/configs/protocol-full.yaml");
  p.sample_rate_Hz = Pick<double>(&rng, {250, 500, 1000, 2000, 5000});
  p.sensors["x"].quantization = Pick<double>(&rng, {0.0, 1e-5, 2e-5});
  d.staircase_step_V = p.valve_step_V = Pick<double>(&rng, {0.04, 0.05, 0.1});
  p.valve_hold_s = Uniform(&rng, 0.2, 0.4);
  p.tube_lengths_m = {0.38};
  if (Uniform(&rng, 0, 1) < 0.5) p.tube_lengths_m.push_back(Pick<double>(&rng, {0.09, 0.9, 1.2}));
  int shape = std::uniform_int_distribution<int>(0, 3)(rng);
  const double on = Uniform(&rng, 0.05, 0.2), level = Uniform(&rng, 0.6, 1.0);
  const char* shapes[] = {"step", "on-off", "two levels", "staircase", "ramp"};
  switch (shape) {
    case 0:
      p.pipeline_schedule = {{on, level}};
      break;
    case 1:
      p.pipeline_schedule = {{on, level}, {on + Uniform(&rng, 0.6, 1.0), 0.0}};
      break;
    case 2:
      p.pipeline_schedule = {{on, 0.5 * level}, {on + Uniform(&rng, 0.5, 0.8), level}};
      break;
    default:
      p.pipeline_schedule = {
          {on, 0.3}, {on + 0.4, 0.6}, {on + 0.8, 1.0}, {on + 1.2, 0.4}, {on + 1.6, 0}};
  }
  p.pipeline_duration_s = p.pipeline_schedule.back().first + 0.8;
  const bool low_only = Uniform(&rng, 0, 1) < 0.25;
  p.stroke_levels_V.clear();
  const int levels = std::uniform_int_distribution<int>(3, 5)(rng);
  for (int k = 0; k < levels; ++k) {
    p.stroke_levels_V.push_back(low_only ? Uniform(&rng, 0.3, 0.45) : Uniform(&rng, 0.35, 1.0));
  }
  p.stroke_cycles = std::uniform_int_distribution<int>(1, 3)(rng);
  p.stroke_margin_m = Pick<double>(&rng, {0.0, 0.001, 0.005});
  p.stroke_dwell_s = p.stroke_margin_m == 0 ? 0.1 : 0.0;
  p.stroke_max_leg_s = 2.0;
  p.paper_step = p.rich_profile = true;
  p.mismatch.regularized_friction = Uniform(&rng, 0, 1) < 0.75;
  // A smooth law creeps below the stick velocity where a real seal holds:
  // up to 0.2 mm/s (a rig's stick is not an event either).
  p.mismatch.stick_velocity_m_per_s = LogUniform(&rng, 2e-5, 2e-4);
  p.mismatch.relative_tolerance = 1e-8;
  // Drawn from a stream of their own (session 16), so that the draws above
  // stay those of the earlier sessions: a third of the valve tests are ramps
  // (no plateau held), a quarter of the units' loggers drop rows.
  std::mt19937_64 logger(seed * 1000003ULL + static_cast<std::uint64_t>(index) + 0x5bd1e995ULL);
  if (Uniform(&logger, 0, 1) < 1.0 / 3.0) {
    p.valve_ramp_s = Uniform(&logger, 3, 10);
    d.staircase_step_V = ValveFitOptions{}.node_spacing_V;
  }
  if (Uniform(&logger, 0, 1) < 0.25) p.dropped_samples = LogUniform(&logger, 0.002, 0.02);
  // A sixth of the tube tests are a ramp up and down in 10 ms steps (no level held).
  if (Uniform(&logger, 0, 1) < 1.0 / 6.0) {
    const double ramp_s = Uniform(&logger, 0.4, 1.0), top = Uniform(&logger, 0.6, 1.0);
    const int steps = static_cast<int>(std::lround(ramp_s / 0.01));
    p.pipeline_schedule.clear();
    for (int k = 0; k <= steps; ++k)
      p.pipeline_schedule.push_back({on + 0.01 * k, top * k / steps});
    for (int k = 1; k <= steps; ++k)
      p.pipeline_schedule.push_back({on + ramp_s + 0.01 * k, top * (steps - k) / steps});
    p.pipeline_duration_s = p.pipeline_schedule.back().first + 0.8;
    shape = 4;
  }
  char valve[48], dropped[48] = "";
  if (p.valve_ramp_s > 0) {
    std::snprintf(valve, sizeof(valve), "valve ramp %.1f s", p.valve_ramp_s);
  } else {
    std::snprintf(valve, sizeof(valve), "valve staircase %.2f V", p.valve_step_V);
  }
  if (p.dropped_samples > 0)
    std::snprintf(dropped, sizeof(dropped), ", %.1f %% rows dropped", 100 * p.dropped_samples);
  char line[480];
  std::snprintf(
      line, sizeof(line),
      "%s %.2f kg, u_sat %.2f, delta %.1f, %s, %.0f Hz%s, %s, tube %s, strokes %s x%d margin %.0f "
      "mm, %s",
      t.cylinder.orientation == Orientation::kVertical ? "vert" : "horiz", t.cylinder.load_mass_kg,
      u_sat, t.pipeline.delta_per_s, FrictionLine(t.friction).c_str(), p.sample_rate_Hz, dropped,
      valve, shapes[shape], low_only ? "low" : "spread", p.stroke_cycles, p.stroke_margin_m * 1e3,
      p.mismatch.regularized_friction ? "smooth stick" : "event stick");
  d.summary = line;
  return d;
}

}  // namespace pneumaid::sweep
