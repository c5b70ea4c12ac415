#include "pneumaid/io/trajectory_csv.h"

#include <sstream>
#include <utility>
#include <vector>

#include "pneumaid/io/files.h"
#include "pneumaid/io/params_yaml.h"

namespace pneumaid {

std::string TrajectoryToCsv(const Trajectory& trajectory, const std::string& comment) {
  const std::vector<std::pair<const char*, const std::vector<double>*>> channels = {
      {"t", &trajectory.t_s},
      {"u", &trajectory.u_V},
      {"x", &trajectory.x_m},
      {"v", &trajectory.v_m_per_s},
      {"p1", &trajectory.p1_Pa},
      {"p2", &trajectory.p2_Pa},
      {"q1 [kg/s]", &trajectory.q1_kg_per_s},
      {"q2 [kg/s]", &trajectory.q2_kg_per_s}};
  std::ostringstream out;
  std::istringstream comment_lines(comment);
  for (std::string line; std::getline(comment_lines, line);) out << "# " << line << "\n";
  std::vector<const std::vector<double>*> present;
  for (const auto& [name, values] : channels) {
    if (values->empty()) continue;
    out << (present.empty() ? "" : ",") << name;
    present.push_back(values);
  }
  out << "\n";
  for (std::size_t row = 0; row < trajectory.size(); ++row) {
    for (std::size_t i = 0; i < present.size(); ++i) {
      out << (i ? "," : "") << FormatDouble((*present[i])[row]);
    }
    out << "\n";
  }
  return out.str();
}

void WriteTrajectoryCsv(const Trajectory& trajectory, const std::string& comment,
                        const std::string& path) {
  WriteFileAtomically(path, TrajectoryToCsv(trajectory, comment));
}

}  // namespace pneumaid
