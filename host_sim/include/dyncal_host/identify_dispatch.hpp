#pragma once
// Maps a runtime term set to the compiled identification models of one robot.

#include "dyncal/friction.hpp"
#include "dyncal_host/identify_pipeline.hpp"

namespace dyncal::host {

/// The term sets `dyncal identify` supports: Eq. 7 or Eq. 8 friction, each with or without
/// rotor inertia and offset.
template <class Robot>
IdentifyResult dispatch_identify(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& o) {
  constexpr unsigned ia = term::rotor_inertia, off = term::offset;
  switch (o.terms) {
    case kFrictionEq7:
      return run_identify<Robot, kFrictionEq7>(robot, log, o);
    case kFrictionEq7 | ia:
      return run_identify<Robot, kFrictionEq7 | ia>(robot, log, o);
    case kFrictionEq7 | off:
      return run_identify<Robot, kFrictionEq7 | off>(robot, log, o);
    case kFrictionEq7 | ia | off:
      return run_identify<Robot, kFrictionEq7 | ia | off>(robot, log, o);
    case kFrictionEq8:
      return run_identify<Robot, kFrictionEq8>(robot, log, o);
    case kFrictionEq8 | ia:
      return run_identify<Robot, kFrictionEq8 | ia>(robot, log, o);
    case kFrictionEq8 | off:
      return run_identify<Robot, kFrictionEq8 | off>(robot, log, o);
    case kFrictionEq8 | ia | off:
      return run_identify<Robot, kFrictionEq8 | ia | off>(robot, log, o);
    default:
      throw InputError("model '" + model_name(o.terms) +
                       "' is not built: use Coulomb + viscous (eq7) or eq8, optionally with rotor_inertia and offset");
  }
}

/// The stacked data (filtered, decimated regressor of the declared model) for the same term sets.
template <class Robot>
StackedData dispatch_prepare(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& o) {
  constexpr unsigned ia = term::rotor_inertia, off = term::offset;
  switch (o.terms) {
    case kFrictionEq7:
      return IdentifyPipeline<Robot, kFrictionEq7>(robot, o).prepare(log);
    case kFrictionEq7 | ia:
      return IdentifyPipeline<Robot, kFrictionEq7 | ia>(robot, o).prepare(log);
    case kFrictionEq7 | off:
      return IdentifyPipeline<Robot, kFrictionEq7 | off>(robot, o).prepare(log);
    case kFrictionEq7 | ia | off:
      return IdentifyPipeline<Robot, kFrictionEq7 | ia | off>(robot, o).prepare(log);
    default:
      throw InputError("declared model '" + model_name(o.terms) +
                       "' is not built for diagnosis: use eq7, optionally with rotor_inertia and offset");
  }
}

}  // namespace dyncal::host
