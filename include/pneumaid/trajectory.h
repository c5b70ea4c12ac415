// One type for measured and simulated runs, so that comparison, residuals and
// plots never convert. Plain data: columns of equal length, SI units, x from
// mid-stroke, pressures absolute, flows as mass flows into each chamber. A
// channel that was not measured is an empty vector.
#pragma once

#include <cstddef>
#include <vector>

namespace pneumaid {

struct Trajectory {
  std::vector<double> t_s;
  std::vector<double> u_V;
  std::vector<double> x_m;
  std::vector<double> v_m_per_s;
  std::vector<double> p1_Pa;
  std::vector<double> p2_Pa;
  std::vector<double> q1_kg_per_s;
  std::vector<double> q2_kg_per_s;

  std::size_t size() const { return t_s.size(); }
};

// The channels a measured and a simulated run are compared on.
struct TrajectoryChannel {
  const char* name;
  std::vector<double> Trajectory::*values;
};
inline constexpr TrajectoryChannel kComparedChannels[] = {{"x", &Trajectory::x_m},
                                                          {"p1", &Trajectory::p1_Pa},
                                                          {"p2", &Trajectory::p2_Pa},
                                                          {"q1", &Trajectory::q1_kg_per_s},
                                                          {"q2", &Trajectory::q2_kg_per_s}};

}  // namespace pneumaid
