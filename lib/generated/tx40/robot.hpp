// GENERATED FILE - DO NOT EDIT.
// Generator: codegen/generate.py (dyncal codegen 5, SymPy 1.11.1)
// Robot: tx40; inputs: robots/tx40/robot.json (sha256 fdac684fe7e00f95), robots/tx40/tx40.urdf (sha256 3d00cbd46279c915)
// Contents: the Robot traits type gathering the generated model
// Include as "dyncal/generated/tx40/<file>.hpp".
// Regenerate: cmake --build <build> --target regenerate (or scripts/codegen).
#pragma once

#include "dynamics.hpp"
#include "dyncal/robot_model.hpp"
#include "parameters.hpp"
#include "regressor.hpp"

namespace dyncal::generated::tx40 {

/// The generated tx40 model as one type, for templates in lib/: meets dyncal/robot_model.hpp.
struct Robot {
  static constexpr const char* kName = kRobotName;
  static constexpr std::uint32_t kRobotId = dyncal::generated::tx40::kRobotId;
  static constexpr int kNumJoints = dyncal::generated::tx40::kNumJoints;
  static constexpr int kNumStandard = dyncal::generated::tx40::kNumStandard;
  static constexpr int kNumBase = dyncal::generated::tx40::kNumBase;

  template <typename Scalar>
  using JointVector = Eigen::Matrix<Scalar, kNumJoints, 1>;

  /// Whether joint j's (0-based) rotor inertia is a base parameter of its own.
  static constexpr bool rotor_inertia_separate(int j) { return kRotorInertiaSeparate[j]; }
  /// Base parameter that absorbs joint j's rotor inertia when it is not separate (else -1).
  static constexpr int rotor_inertia_absorbed_into(int j) { return kRotorInertiaAbsorbedInto[j]; }
  static constexpr const char* base_param_name(int i) { return kBaseParamNames[i]; }
  /// First and last row (0-based joint) where base column b can be nonzero (kBaseColumnRows).
  static constexpr int base_column_first_row(int b) { return kBaseColumnRows[b][0]; }
  static constexpr int base_column_last_row(int b) { return kBaseColumnRows[b][1]; }
  /// Whether joint j (0-based) is prismatic (q [m], tau [N]) rather than revolute (q [rad], tau [Nm]).
  static constexpr bool joint_prismatic(int j) { return kJointPrismatic[j]; }
  /// Gravity [m/s^2] along base axis i.
  static constexpr double gravity(int i) { return kGravity[i]; }
  static constexpr const char* standard_param_name(int i) { return kStandardParamNames[i]; }

  template <typename Scalar>
  static void standard_regressor(const JointVector<Scalar>& q, const JointVector<Scalar>& qd,
                                 const JointVector<Scalar>& qdd,
                                 Eigen::Matrix<Scalar, kNumJoints, kNumStandard>& Y) noexcept {
    dyncal::generated::tx40::standard_regressor(q, qd, qdd, Y);
  }
  /// Writes Y_b into the first kNumBase columns of Yb (Cols >= kNumBase; the rest is untouched).
  template <typename Scalar, int Cols>
  static void base_regressor(const JointVector<Scalar>& q, const JointVector<Scalar>& qd,
                             const JointVector<Scalar>& qdd, Eigen::Matrix<Scalar, kNumJoints, Cols>& Yb) noexcept {
    dyncal::generated::tx40::base_regressor(q, qd, qdd, Yb);
  }
  template <typename Scalar>
  static void inverse_dynamics(const JointVector<Scalar>& q, const JointVector<Scalar>& qd,
                               const JointVector<Scalar>& qdd,
                               const Eigen::Matrix<Scalar, kNumStandard, 1>& phi,
                               JointVector<Scalar>& tau) noexcept {
    dyncal::generated::tx40::inverse_dynamics(q, qd, qdd, phi, tau);
  }
  template <typename Scalar>
  static void mass_matrix(const JointVector<Scalar>& q, const Eigen::Matrix<Scalar, kNumStandard, 1>& phi,
                          Eigen::Matrix<Scalar, kNumJoints, kNumJoints>& M) noexcept {
    dyncal::generated::tx40::mass_matrix(q, phi, M);
  }
  template <typename Scalar>
  static void standard_to_base(const Eigen::Matrix<Scalar, kNumStandard, 1>& phi,
                               Eigen::Matrix<Scalar, kNumBase, 1>& phi_b) noexcept {
    dyncal::generated::tx40::standard_to_base(phi, phi_b);
  }
};

static_assert(dyncal::is_robot_model_v<Robot>, "the generated tx40 model does not meet dyncal/robot_model.hpp");

}  // namespace dyncal::generated::tx40
