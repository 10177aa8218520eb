#pragma once
// Maps a runtime term set to the compiled identification models of one robot.

#include "dyncal_host/common/model_terms.hpp"
#include "dyncal_host/identification/identify_pipeline.hpp"

namespace dyncal::host {

template <class Robot>
struct IdentifyWith {
  template <unsigned Terms>
  struct Run {
    static IdentifyResult run(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& o) {
      return run_identify<Robot, Terms>(robot, log, o);
    }
  };
  template <unsigned Terms>
  struct Prepare {
    static StackedData run(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& o) {
      return IdentifyPipeline<Robot, Terms>(robot, o).prepare(log);
    }
  };
};

/// `dyncal identify` for one robot, over the built term sets (model_terms.hpp).
template <class Robot>
IdentifyResult dispatch_identify(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& o) {
  return with_term_set<IdentifyWith<Robot>::template Run>(o.terms, robot, log, o);
}

/// The stacked data (filtered, decimated regressor of the declared model) for the same term sets.
template <class Robot>
StackedData dispatch_prepare(const RobotDescription& robot, const JointLog& log, const IdentifyOptions& o) {
  return with_term_set<IdentifyWith<Robot>::template Prepare>(o.terms, robot, log, o);
}

}  // namespace dyncal::host
