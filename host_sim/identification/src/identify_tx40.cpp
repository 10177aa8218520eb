#include "dyncal/generated/tx40/robot.hpp"
#include "dyncal_host/identification/identify_dispatch.hpp"

namespace dyncal::host {

IdentifyResult identify_tx40(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& options) {
  return dispatch_identify<dyncal::generated::tx40::Robot>(robot, log, options);
}

StackedData prepare_tx40(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& options) {
  if (log.joints() != dyncal::generated::tx40::Robot::kNumJoints)
    throw InputError("log joint count does not match the robot");
  return dispatch_prepare<dyncal::generated::tx40::Robot>(robot, log, options);
}

}  // namespace dyncal::host
