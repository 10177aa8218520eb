#include "dyncal_host/identify_dispatch.hpp"
#include "er20/robot.hpp"

namespace dyncal::host {

IdentifyResult identify_er20(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& options) {
  return dispatch_identify<dyncal::generated::er20::Robot>(robot, log, options);
}

StackedData prepare_er20(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& options) {
  if (log.joints() != dyncal::generated::er20::Robot::kNumJoints)
    throw InputError("log joint count does not match the robot");
  return dispatch_prepare<dyncal::generated::er20::Robot>(robot, log, options);
}

}  // namespace dyncal::host
