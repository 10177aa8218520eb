#pragma once

#include <Eigen/Core>
#include <string>
#include <utility>
#include <vector>

namespace dyncal::host {

/// A measured or simulated log on the joint side. Rows are samples, columns joints (joint 1
/// first). Units: t [s], q [rad], qd [rad/s], qdd [rad/s^2], tau [Nm]. Time strictly increases.
/// A log may consist of segments (several logs, or one split at a gap): signals are never filtered
/// or differentiated across a segment boundary. As read, time stamps may jitter and samples be
/// missing; identification puts the log on a uniform grid first (uniform_grid.hpp).
struct JointLog {
  Eigen::VectorXd t;
  Eigen::MatrixXd q, qd, qdd, tau;
  bool has_qd = false;   ///< qd was measured (else computed)
  bool has_qdd = false;  ///< qdd was measured (else computed)
  std::string source;
  std::vector<Eigen::Index> segment_starts;  ///< first row of each segment after the first (empty: one segment)
  double period = 0;                         ///< uniform grid period [s] of every segment; 0: not on a grid

  Eigen::Index samples() const { return t.size(); }
  int joints() const { return static_cast<int>(q.cols()); }
  /// The grid period if set, else the mean step of the log.
  double sample_period() const {
    return period > 0 ? period : (t[t.size() - 1] - t[0]) / static_cast<double>(t.size() - 1);
  }
  /// [first row, end row) of every segment, in order.
  std::vector<std::pair<Eigen::Index, Eigen::Index>> segments() const {
    std::vector<std::pair<Eigen::Index, Eigen::Index>> out;
    Eigen::Index a = 0;
    for (const Eigen::Index b : segment_starts) {
      out.emplace_back(a, b);
      a = b;
    }
    out.emplace_back(a, samples());
    return out;
  }
  /// Total duration of the segments [s] (each as its sample count times the period).
  double duration() const { return static_cast<double>(samples()) * sample_period(); }
};

/// Reads a CSV log with a header `t, q1..qN, [qd1..qdN], [qdd1..qddN], tau1..tauN` (any column
/// order, names as given, 1-based joints). Time stamps may jitter and rows be missing (see
/// uniform_grid.hpp). Throws InputError naming the problem: unreadable file, missing column, wrong
/// joint count (N != expected_joints), a non-numeric or non-finite value (with its line and column),
/// time not strictly increasing (with its row), fewer than 3 samples.
JointLog read_csv_log(const std::string& path, int expected_joints);

/// Reads a CSV log of motor currents: as read_csv_log with columns `i1..iN` [A] (motor k's current
/// in column ik) in place of `tau1..tauN`. Joint torque tau = N^T diag(Kt) i [Nm]: each motor's
/// torque Kt_k i_k reflected to the joints by the transpose of the transmission matrix N (q_motor =
/// N q; coupled motors included). Friction and rotor inertia stay in the fitted model (they are not
/// subtracted here). Throws InputError as read_csv_log, and when `torque_constants` is not one per
/// motor (the robot file gives none).
JointLog read_current_csv_log(const std::string& path, const Eigen::MatrixXd& transmission,
                              const Eigen::VectorXd& torque_constants);

/// Converts a log whose `tau` holds motor currents [A] (motor k's in column k) to joint torque,
/// tau = N^T diag(Kt) i [Nm]: each motor's torque Kt_k i_k reflected to the joints by the transpose
/// of the transmission matrix N (q_motor = N q; coupled motors included). Friction and rotor inertia
/// stay in the fitted model. Throws InputError naming `what` (the log) when `torque_constants` is not
/// one per motor (the robot file gives none).
void current_to_joint_torque(JointLog& log, const Eigen::MatrixXd& transmission,
                             const Eigen::VectorXd& torque_constants, const std::string& what);

/// Throws InputError naming `what` unless `t` has at least 3 samples and strictly increases.
void check_log_time(const Eigen::VectorXd& t, const std::string& what);

/// A log of `rows` samples (values unset) with the columns of `like`: its joints, measured qd and qdd,
/// its source; one segment, no grid period.
JointLog sized_like(const JointLog& like, Eigen::Index rows);

/// Writes `log` as a CSV that read_csv_log reads back exactly: header `t, q1..qN, [qd1..qdN,]
/// [qdd1..qddN,] tau1..tauN` (qd, qdd only when measured), 17 significant digits. Throws
/// InputError when the file cannot be written.
void write_csv_log(const std::string& path, const JointLog& log);

/// Reads the TX40 data set (`pos_read_data.csv`: motor positions [rad]; `curr_data.csv`: motor
/// torques [Nm]; 5 kHz, no time column) from `folder` and converts it to the joint side:
/// q = N^-1 q_m + offsets, tau = N^T tau_m, with N the robot's transmission matrix.
JointLog read_tx40_log(const std::string& folder, const Eigen::MatrixXd& transmission,
                       const Eigen::VectorXd& joint_offsets, double sample_rate_hz = 5000.0);

}  // namespace dyncal::host
