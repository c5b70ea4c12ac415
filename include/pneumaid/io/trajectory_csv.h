// Trajectories as CSV logs of the rig-data format (kind: validation).
#pragma once

#include <string>

#include "pneumaid/trajectory.h"

namespace pneumaid {

// `t,u,x,v,p1,p2,q1 [kg/s],q2 [kg/s]` in SI (x from mid-stroke, pressures
// absolute, mass flows), so that the file is itself a valid validation log.
// Channels that are empty are left out. `comment` lines go first, each
// prefixed with "# ".
std::string TrajectoryToCsv(const Trajectory& trajectory, const std::string& comment);

// Writes TrajectoryToCsv atomically.
void WriteTrajectoryCsv(const Trajectory& trajectory, const std::string& comment,
                        const std::string& path);

}  // namespace pneumaid
