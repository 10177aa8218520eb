#include "dyncal_host/logs/torque_delay.hpp"

#include <algorithm>
#include <string>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {

void undo_torque_delay(JointLog& log, const TorqueDelay& delay) {
  const int j = delay.joint;
  if (j < 0 || j >= log.joints())
    throw InputError("torque delay: joint " + std::to_string(j + 1) + " is not in the log (" +
                     std::to_string(log.joints()) + " joints)");
  if (delay.seconds == 0.0) return;
  const Eigen::VectorXd tau = log.tau.col(j);
  for (const auto& [a, b] : log.segments()) {
    Eigen::Index k = a;  // the sample at or before the instant read, walking forward with s
    for (Eigen::Index s = a; s < b; ++s) {
      const double when = log.t[s] + delay.seconds;
      if (when <= log.t[a]) {
        log.tau(s, j) = tau[a];
        continue;
      }
      if (when >= log.t[b - 1]) {
        log.tau(s, j) = tau[b - 1];
        continue;
      }
      while (k + 1 < b - 1 && log.t[k + 1] <= when) ++k;
      while (k > a && log.t[k] > when) --k;
      const double span = log.t[k + 1] - log.t[k];
      const double u = span > 0 ? (when - log.t[k]) / span : 0.0;
      log.tau(s, j) = (1 - u) * tau[k] + u * tau[k + 1];
    }
  }
}

}  // namespace dyncal::host
