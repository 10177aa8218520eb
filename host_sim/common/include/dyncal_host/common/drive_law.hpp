#pragma once
// The control law a log was recorded under, as IDIM-IV needs it (Gautier, Janot and Vandanjon 2013):
// the drive's PD gains, the feed-forward table it had active and the trajectory it played, for a
// run of dyncal's drive: PD on the encoder position and its backward difference plus the table's
// inverse-dynamics feed-forward (survey Fig. 3). Identification reads it from a law file
// (logs/drive_law.hpp), the simulated drive plays it (drive/closed_loop.hpp).

#include <string>
#include <vector>

#include "dyncal/parameter_table.hpp"
#include "dyncal_host/common/excitation_trajectory.hpp"

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

}  // namespace dyncal::host
