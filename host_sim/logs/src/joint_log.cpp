#include "dyncal_host/logs/joint_log.hpp"

#include <Eigen/LU>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <utility>
#include <vector>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/output_file.hpp"
#include "dyncal_host/logs/numeric_csv.hpp"

namespace dyncal::host {

void check_log_time(const Eigen::VectorXd& t, const std::string& path) {
  if (t.size() < 3) throw InputError(path + ": fewer than 3 samples");
  for (Eigen::Index i = 1; i < t.size(); ++i) {
    if (!(t[i] > t[i - 1])) {
      throw InputError(path + ": time is not strictly increasing at data row " + std::to_string(i + 1) +
                       " (t = " + std::to_string(t[i]) + " s after " + std::to_string(t[i - 1]) + " s)");
    }
  }
}

JointLog sized_like(const JointLog& like, Eigen::Index rows) {
  const int n = like.joints();
  JointLog out;
  out.has_qd = like.has_qd;
  out.has_qdd = like.has_qdd;
  out.source = like.source;
  out.t.resize(rows);
  out.q.resize(rows, n);
  out.tau.resize(rows, n);
  if (out.has_qd) out.qd.resize(rows, n);
  if (out.has_qdd) out.qdd.resize(rows, n);
  return out;
}

void write_csv_log(const std::string& path, const JointLog& log) {
  std::ostringstream out;
  const int n = log.joints();
  std::vector<std::pair<const Eigen::MatrixXd*, std::string>> blocks{{&log.q, "q"}};
  if (log.has_qd) blocks.emplace_back(&log.qd, "qd");
  if (log.has_qdd) blocks.emplace_back(&log.qdd, "qdd");
  blocks.emplace_back(&log.tau, "tau");
  out << "t";
  for (const auto& b : blocks) {
    for (int j = 1; j <= n; ++j) out << ',' << b.second << j;
  }
  out << '\n';
  char number[32];
  for (Eigen::Index s = 0; s < log.samples(); ++s) {
    std::snprintf(number, sizeof number, "%.17g", log.t[s]);
    out << number;
    for (const auto& b : blocks) {
      for (int j = 0; j < n; ++j) {
        std::snprintf(number, sizeof number, ",%.17g", (*b.first)(s, j));
        out << number;
      }
    }
    out << '\n';
  }
  write_output_file(path, out.str(), "log");
}

namespace {

/// read_csv_log with the torque columns named `effort` (tau or i) followed by the joint number.
JointLog read_csv_columns(const std::string& path, int expected_joints, const std::string& effort) {
  const NumericCsv csv = read_numeric_csv(path);
  std::map<std::string, Eigen::Index> col = column_index(csv, path);
  auto count = [&](const std::string& prefix) {
    int n = 0;
    while (col.count(prefix + std::to_string(n + 1))) ++n;
    return n;
  };
  if (!col.count("t")) throw InputError(path + ": missing column 't'");
  const int nq = count("q"), ntau = count(effort);
  if (nq == 0) throw InputError(path + ": missing column 'q1'");
  if (nq != expected_joints) {
    throw InputError(path + ": " + std::to_string(nq) + " joints (q1..q" + std::to_string(nq) + "), robot has " +
                     std::to_string(expected_joints));
  }
  for (int j = 1; j <= expected_joints; ++j) {
    if (!col.count(effort + std::to_string(j)))
      throw InputError(path + ": missing column '" + effort + std::to_string(j) + "'" +
                       (effort == "i" ? " (motor current, --torque-from current)" : ""));
  }
  if (ntau != expected_joints)
    throw InputError(path + ": " + std::to_string(ntau) + (effort == "i" ? " current" : " torque") +
                     " columns, robot has " + std::to_string(expected_joints));
  const int nqd = count("qd"), nqdd = count("qdd");
  for (auto [name, n] : {std::pair<const char*, int>{"qd", nqd}, {"qdd", nqdd}}) {
    if (n != 0 && n != expected_joints) {
      throw InputError(path + ": missing column '" + std::string(name) + std::to_string(n + 1) + "' (give all " +
                       std::to_string(expected_joints) + " or none)");
    }
  }
  JointLog log;
  log.source = path;
  const Eigen::Index rows = csv.values.rows();
  log.t = csv.values.col(col["t"]);
  check_log_time(log.t, path);
  auto block = [&](const std::string& prefix) {
    Eigen::MatrixXd m(rows, expected_joints);
    for (int j = 0; j < expected_joints; ++j) m.col(j) = csv.values.col(col[prefix + std::to_string(j + 1)]);
    return m;
  };
  log.q = block("q");
  log.tau = block(effort);
  log.has_qd = nqd > 0;
  log.has_qdd = nqdd > 0;
  if (log.has_qd) log.qd = block("qd");
  if (log.has_qdd) log.qdd = block("qdd");
  return log;
}

}  // namespace

JointLog read_csv_log(const std::string& path, int expected_joints) {
  return read_csv_columns(path, expected_joints, "tau");
}

JointLog read_current_csv_log(const std::string& path, const Eigen::MatrixXd& transmission,
                              const Eigen::VectorXd& torque_constants) {
  const int n = static_cast<int>(transmission.rows());
  if (torque_constants.size() != n) {
    throw InputError(path +
                     ": --torque-from current needs the robot's transmission.torque_constants (Nm/A "
                     "per motor, docs/robots.md)");
  }
  JointLog log = read_csv_columns(path, n, "i");
  current_to_joint_torque(log, transmission, torque_constants, path);
  return log;
}

void current_to_joint_torque(JointLog& log, const Eigen::MatrixXd& transmission,
                             const Eigen::VectorXd& torque_constants, const std::string& what) {
  if (torque_constants.size() != transmission.rows()) {
    throw InputError(what +
                     ": motor currents need the robot's transmission.torque_constants (Nm/A "
                     "per motor, docs/robots.md)");
  }
  // tau_m = Kt i per motor; tau = N^T tau_m   (rows are samples: Tau = I diag(Kt) N)
  log.tau = log.tau * torque_constants.asDiagonal() * transmission;
  log.source += " (torque from motor current: tau = N^T diag(Kt) i)";
}

JointLog read_tx40_log(const std::string& folder, const Eigen::MatrixXd& transmission,
                       const Eigen::VectorXd& joint_offsets, double sample_rate_hz) {
  const NumericCsv pos = read_numeric_csv(folder + "/pos_read_data.csv");
  const NumericCsv cur = read_numeric_csv(folder + "/curr_data.csv");
  const Eigen::Index n = transmission.rows();
  if (pos.values.cols() != n || cur.values.cols() != n) {
    throw InputError(folder + ": TX40 files have " + std::to_string(pos.values.cols()) + " and " +
                     std::to_string(cur.values.cols()) + " columns, robot has " + std::to_string(n) + " joints");
  }
  if (pos.values.rows() != cur.values.rows()) {
    throw InputError(folder + ": pos_read_data.csv has " + std::to_string(pos.values.rows()) +
                     " rows but curr_data.csv has " + std::to_string(cur.values.rows()));
  }
  if (pos.values.rows() < 3) throw InputError(folder + ": fewer than 3 samples");
  JointLog log;
  log.source = folder + " (TX40 format)";
  const Eigen::Index rows = pos.values.rows();
  log.t = Eigen::VectorXd::LinSpaced(rows, 0.0, static_cast<double>(rows - 1) / sample_rate_hz);
  // q = N^-1 q_m + offset ; tau = N^T tau_m   (rows are samples: Q = Qm N^-T, Tau = Taum N)
  const Eigen::MatrixXd n_inv = transmission.inverse();
  log.q = pos.values * n_inv.transpose();
  log.q.rowwise() += joint_offsets.transpose();
  log.tau = cur.values * transmission;
  return log;
}

}  // namespace dyncal::host
