// A probe for the dependency rule's sublayers, never compiled: a method (the lower sublayer of
// identification) including the pipeline above it. CTest host_sim_dependency_rule_catches_a_climb runs
// the rule on this folder and passes only when the rule names this include.
#include "dyncal_host/identification/pipeline/identify.hpp"
