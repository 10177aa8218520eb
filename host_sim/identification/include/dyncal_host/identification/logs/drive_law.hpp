#pragma once
// The control law a log was recorded under, as IDIM-IV needs it (Gautier, Janot and Vandanjon 2013):
// the drive's PD gains, the feed-forward table it had active and the trajectory it played. A law
// file (docs/cli.md "Law file", identify --law) describes a run of dyncal's drive: PD on the
// encoder position and its backward difference plus the table's inverse-dynamics feed-forward
// (survey Fig. 3).

#include <cstdint>
#include <string>
#include <vector>

#include "dyncal/parameter_table.hpp"
#include "dyncal_host/common/excitation_trajectory.hpp"
#include "dyncal_host/common/robot_description.hpp"

namespace dyncal::host {

struct DriveLaw {
  ExcitationTrajectory trajectory;  ///< the Fourier trajectory played (Eq. 27), t = 0 at its start
  int periods = 1;                  ///< periods played
  double sample_rate_hz = 0;        ///< the log's rate [Hz]: sample k at t = k / rate
  double control_rate_hz = 0;       ///< the control loop's rate [Hz]; 0: the drive's default
  std::vector<double> kp, kd;       ///< PD gains per joint [Nm/rad], [Nm s/rad]
  bool has_table = false;           ///< false: the factory table (robot.json's inertials, no friction)
  ParameterTable table;             ///< the feed-forward table active during the run
  std::string source;               ///< the file
};

/// Reads a law file: {"trajectory": an excite file's object or its path (relative to the law
/// file), "periods", "sample_rate_hz", "kp": [N], "kd": [N], optional "control_rate_hz" and
/// "feed_forward": an identify --params file's path or "feed_forward_table": a table file's path
/// (the encoded table as the drive held it, calibrate --save-law; CRC-checked; absent: the factory
/// table)}. Paths relative to the law file. Throws InputError
/// naming the file and the field: not JSON, a field missing or of the wrong type or length, gains not
/// finite and positive, rates not positive, a trajectory outside the robot's limits, parameters of
/// another robot.
DriveLaw read_drive_law(const std::string& path, const RobotDescription& robot);

}  // namespace dyncal::host
