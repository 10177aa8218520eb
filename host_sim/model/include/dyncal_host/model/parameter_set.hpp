#pragma once
// A set of identified parameters and its file (`dyncal identify --params`, docs/cli.md): what
// predict, diagnose, payload, monitor, export and the drive table read back.

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "dyncal_host/common/model_effects.hpp"
#include "dyncal_host/model/identify_result.hpp"

namespace dyncal::host {

/// Identified parameters of one robot and model, in the model's parameter order.
struct ParameterSet {
  std::string robot, model, source;
  unsigned terms = 0;                ///< dyncal::term bits of `model`
  std::vector<ModelEffect> effects;  ///< effect terms of `model` after the compiled ones (model_effects.hpp)
  std::vector<CoupledMotor> motors;  ///< coupled motors of `model` (their terms are the compiled ones)
  bool friction_per_motor = false;   ///< "friction_per": "motor" (robot.json's coupling modelled) or "joint"
  std::vector<std::string> names;    ///< the compiled robot's parameter names for the terms, then the effects'
  Eigen::VectorXd values;
  /// Standard deviation of each value as identify reported it (NaN where the file gives none or the
  /// parameter was not determined); empty when the values are not an identification's.
  Eigen::VectorXd stdev;
  /// Each link's consistent inertials (identify --method pcls; file key "links"), empty when the set
  /// has none (other methods: the base parameters do not determine them).
  std::vector<LinkInertial> links;
  /// A set identified from motor currents (file key "torque_constants"): each motor's torque
  /// constant [Nm/A] the logs were converted with, its std [Nm/A] (NaN: a nominal value without
  /// one, robot.json's) and where they come from; empty for a set identified from joint torques.
  /// Logs of currents the set is applied to are converted with the same constants (payload).
  Eigen::VectorXd torque_constants, torque_constants_std;
  std::string torque_constants_source;
  /// The reference model a shape of tau_model reads (file key "tau_model_reference"; model_effects.hpp
  /// ShapeVariable): parameters in `values`' order whose torque [W E] reference is the shape's
  /// variable, 0 at the shapes of tau_model (identify's first fit without them). Empty when the
  /// model has no such shape.
  Eigen::VectorXd tau_model_reference;
};

/// Reads a `dyncal identify --params` file (docs/cli.md). Throws InputError with the file and what
/// is wrong: not JSON, not a dyncal parameter file, robot or model missing, a robot not compiled into
/// this build, a model not built, a wrong parameter count, a name that is not the model's parameter
/// at that place, a value that is not a finite number.
ParameterSet read_parameter_file(const std::string& path);

/// The parameter file of `p` (docs/cli.md "--params schema"; read_parameter_file reads it): format,
/// version, robot, model, `method`, friction_per, params [{name, value, std}] (std only when the set
/// has them; null where not determined), links [{link, mass, com, inertia_about_com}] when it has them,
/// torque_constants {source, values, std} when the set has them.
nlohmann::json parameter_file_json(const ParameterSet& p, const std::string& method);

/// A parameter file's "torque_constants" of `p` (it has them): {source, values [Nm/A], std (null where
/// none)}.
nlohmann::json torque_constants_json(const ParameterSet& p);

/// [{link, mass, com, inertia_about_com, pseudo_inertia_min_eigenvalue}]: the "links" of a report
/// and of a parameter file (read_parameter_file reads the latter back).
nlohmann::json link_inertials_json(const std::vector<LinkInertial>& links);

/// The parameters identify reports (IdentifyResult::params) as a set.
ParameterSet parameter_set(const IdentifyResult& r);

/// How many of p's parameters are compiled ones (the rest, after them, are its effects' coefficients).
size_t compiled_parameter_count(const ParameterSet& p);

/// p for a log other than the one it was identified on: a shape of time (variable t or sgn(qdJ)*t,
/// model_effects.hpp) is a change over the identification log, not a property of the arm, so its
/// coefficients become 0; a note for each into *notes.
ParameterSet without_time_shapes(ParameterSet p, std::vector<std::string>* notes);

}  // namespace dyncal::host
