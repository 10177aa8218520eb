#include "dyncal_host/identification/identify.hpp"

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/stacked_data.hpp"

namespace dyncal::host {

IdentifyResult identify(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& options) {
  if (robot.name == "er20") return identify_er20(robot, log, options);
  if (robot.name == "tx40") return identify_tx40(robot, log, options);
  throw InputError("robot '" + robot.name + "' has no generated model in this build (known: er20, tx40)");
}

StackedData prepare_stacked(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& options) {
  if (robot.name == "er20") return prepare_er20(robot, log, options);
  if (robot.name == "tx40") return prepare_tx40(robot, log, options);
  throw InputError("no generated model for robot '" + robot.name + "'");
}

}  // namespace dyncal::host
