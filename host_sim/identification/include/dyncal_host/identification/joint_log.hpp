#pragma once

#include <Eigen/Core>
#include <string>

namespace dyncal::host {

/// A measured or simulated log on the joint side. Rows are samples, columns joints (joint 1
/// first). Units: t [s], q [rad], qd [rad/s], qdd [rad/s^2], tau [Nm]. Sampling is uniform.
struct JointLog {
  Eigen::VectorXd t;
  Eigen::MatrixXd q, qd, qdd, tau;
  bool has_qd = false;   ///< qd was measured (else computed)
  bool has_qdd = false;  ///< qdd was measured (else computed)
  std::string source;

  Eigen::Index samples() const { return t.size(); }
  int joints() const { return static_cast<int>(q.cols()); }
  double sample_period() const { return (t[t.size() - 1] - t[0]) / static_cast<double>(t.size() - 1); }
};

/// Reads a CSV log with a header `t, q1..qN, [qd1..qdN], [qdd1..qddN], tau1..tauN` (any column
/// order, names as given, 1-based joints). Throws InputError naming the problem: unreadable file,
/// missing column, wrong joint count (N != expected_joints), a non-numeric or non-finite value
/// (with its line and column), non-monotonic or non-uniform time, fewer than 3 samples.
JointLog read_csv_log(const std::string& path, int expected_joints);

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
