#pragma once

#include <Eigen/Core>

#include "friction.hpp"
#include "regressor_structure.hpp"
#include "robot_model.hpp"

namespace dyncal {

/// Kind of one identification-model parameter.
enum class ParamKind { base, term };

/// What parameter `index` of an identification model is: a base parameter (`base_index` into the
/// generated kBaseParamNames) or a per-joint term (`term` bit, `joint` 1-based).
struct ParamInfo {
  ParamKind kind;
  int base_index;
  unsigned term;
  int joint;
};

/// The linear identification model tau = [Y_b  K_f] phi (survey Eq. 12): the generated base
/// regressor of `Robot` followed by per-joint term columns (friction Eq. 7-9, rotor inertia,
/// offset) for the term set `Terms` (bits of dyncal::term).
///
/// Parameter order: the Robot's base parameters, then joint 1's terms, joint 2's terms, ...; within
/// a joint, terms in the order coulomb, viscous, power, load, rotor_inertia, offset. Rotor inertia
/// gets its own column only on joints where the generated model marks it separately identifiable
/// (Robot-specific kRotorInertiaSeparate); elsewhere it is absorbed into a base parameter (for
/// example Ia_1 into link1_ZZ_R) and has no column.
template <class Robot, unsigned Terms>
class IdentificationModel {
  static_assert(is_robot_model_v<Robot>, "IdentificationModel needs a robot model (dyncal/robot_model.hpp)");

 public:
  using RobotType = Robot;
  static constexpr unsigned kTerms = Terms;
  static constexpr int kNumJoints = Robot::kNumJoints;
  static constexpr int kNumBase = Robot::kNumBase;

  /// Whether term `t` has a column for joint j (0-based): it is in Terms and, for rotor inertia,
  /// separately identifiable on that joint.
  static constexpr bool has_column(unsigned t, int j) {
    return (Terms & t) != 0u && (t != term::rotor_inertia || Robot::rotor_inertia_separate(j));
  }

  /// Number of columns joint j (0-based) contributes.
  static constexpr int joint_columns(int j) {
    int count = 0;
    for (int i = 0; i < kNumTerms; ++i) {
      const unsigned t = term_bit(i);
      if (!has_column(t, j)) continue;
      ++count;
    }
    return count;
  }
  static constexpr int total_term_columns() {
    int count = 0;
    for (int j = 0; j < kNumJoints; ++j) count += joint_columns(j);
    return count;
  }
  static constexpr int kNumTermColumns = total_term_columns();
  static constexpr int kNumParams = kNumBase + kNumTermColumns;

  template <typename Scalar>
  using JointVector = Eigen::Matrix<Scalar, kNumJoints, 1>;
  template <typename Scalar>
  using Regressor = Eigen::Matrix<Scalar, kNumJoints, kNumParams>;
  template <typename Scalar>
  using ParamVector = Eigen::Matrix<Scalar, kNumParams, 1>;

  /// Column index of term `t` of joint `joint0` (0-based), or -1 when the model has none.
  static constexpr int column(unsigned t, int joint0) {
    int col = kNumBase;
    for (int j = 0; j < kNumJoints; ++j) {
      for (int i = 0; i < kNumTerms; ++i) {
        const unsigned b = term_bit(i);
        if (!has_column(b, j)) continue;
        if (j == joint0 && b == t) return col;
        ++col;
      }
    }
    return -1;
  }

  /// Description of parameter `index` (0 <= index < kNumParams).
  static constexpr ParamInfo info(int index) {
    if (index < kNumBase) return ParamInfo{ParamKind::base, index, 0u, 0};
    int col = kNumBase;
    for (int j = 0; j < kNumJoints; ++j) {
      for (int i = 0; i < kNumTerms; ++i) {
        const unsigned b = term_bit(i);
        if (!has_column(b, j)) continue;
        if (col == index) return ParamInfo{ParamKind::term, -1, b, j + 1};
        ++col;
      }
    }
    return ParamInfo{ParamKind::term, -1, 0u, 0};
  }

  /// Rows where column c of K can be nonzero: the generated structure of the base regressor
  /// (Robot::base_column_first_row/last_row) and joint j's own row for its term columns.
  static constexpr RegressorStructure<kNumParams> structure() {
    RegressorStructure<kNumParams> s{};
    set_base_structure<Robot>(s);
    int col = kNumBase;
    for (int j = 0; j < kNumJoints; ++j) {
      for (int i = 0; i < kNumTerms; ++i) {
        if (!has_column(term_bit(i), j)) continue;
        s.first[col] = static_cast<std::int8_t>(j);
        s.last[col] = static_cast<std::int8_t>(j);
        ++col;
      }
    }
    return s;
  }

  /// Fills K (kNumJoints x kNumParams) at one sample. q [rad], qd [rad/s], qdd [rad/s^2];
  /// tau_load [Nm] is only read by the Eq. 9 term (pass zeros otherwise). Joint-side quantities.
  /// Allocation-free; the generated base regressor writes straight into K's first kNumBase columns.
  template <typename Scalar>
  static void regressor(const JointVector<Scalar>& q, const JointVector<Scalar>& qd, const JointVector<Scalar>& qdd,
                        const JointVector<Scalar>& tau_load, Regressor<Scalar>& K) noexcept {
    Robot::base_regressor(q, qd, qdd, K);
    K.template rightCols<kNumTermColumns>().setZero();
    int col = kNumBase;
    for (int j = 0; j < kNumJoints; ++j) {
      for (int i = 0; i < kNumTerms; ++i) {
        const unsigned b = term_bit(i);
        if (!has_column(b, j)) continue;
        K(j, col++) = term_column(b, qd[j], qdd[j], tau_load[j]);
      }
    }
  }
};

}  // namespace dyncal
