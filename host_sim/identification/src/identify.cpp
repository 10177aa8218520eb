#include "dyncal_host/identification/identify.hpp"

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/identification/compiled_robot.hpp"
#include "dyncal_host/identification/stacked_data.hpp"

namespace dyncal::host {
namespace {

const CompiledRobot& checked(const RobotDescription& robot, const JointLog& log) {
  const CompiledRobot& c = compiled_robot_for(robot);
  if (log.joints() != c.num_joints) {
    throw InputError("the log has " + std::to_string(log.joints()) + " joints, robot '" + robot.name + "' " +
                     std::to_string(c.num_joints));
  }
  return c;
}

}  // namespace

IdentifyResult identify(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& options) {
  const CompiledRobot& c = checked(robot, log);
  return c.identify[static_cast<size_t>(built_term_set_index(options.terms))](robot, log, options);
}

StackedData prepare_stacked(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& options) {
  const CompiledRobot& c = checked(robot, log);
  return c.prepare[static_cast<size_t>(built_term_set_index(options.terms))](robot, log, options);
}

}  // namespace dyncal::host
