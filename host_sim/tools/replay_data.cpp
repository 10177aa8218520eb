// Writes port/replay/er20_replay_data.hpp: a block of simulated er20 drive samples (the simulated
// drive of host_sim with Eq. 4 Stribeck friction and the survey's Table 7 torque noise, recorded at
// 100 Hz over two periods of the default excitation) and the host's double-precision replay of
// the KF, RLS, EKF, friction tracker and payload estimator over them (the reference the firmware images compare
// against). The samples are a recording, not regenerated when the simulated drive changes (the firmware's figures stay
// comparable from one commit to the next); tests/test_firmware_replay.cpp checks that the references are the replay of
// the committed samples. Usage: dyncal_replay_data OUT.hpp   (CMake target `replay-data`: records anew).
//        dyncal_replay_data --references DATA.hpp: the committed recording's references computed
//        again from its own samples (an updater added or changed), the samples kept (CMake target
//        `replay-references`).
//        dyncal_replay_data --ratings OUT.hpp: port/replay/er20_ratings.hpp, the er20's ratings from
//        robots/er20/robot.json for the firmware parameter store's table plausibility, and the arm the
//        drive image simulates (the host's default scenario of the er20) (same target;
//        CTest replay_ratings_up_to_date regenerates it and fails on any difference).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <utility>
#include <vector>

#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/drive/scenario.hpp"
#include "dyncal_host/drive/simulated_drive.hpp"
#include "dyncal_host/excitation/excitation.hpp"
#include "dyncal_host/model/compiled_robot.hpp"
#include "er20_replay_data.hpp"
#include "replay.hpp"

namespace {

using dyncal::replay::Updater;

constexpr std::uint64_t kSeed = 2026;
constexpr double kRate = 100.0;

/// `arm`: the payload estimator's arm parameters (the KF's reference), ignored by the others.
template <Updater U>
std::vector<double> reference(const std::vector<std::array<float, 12>>& samples, const double* sigma,
                              dyncal::replay::Counts& c, const double* arm = nullptr) {
  auto est = std::make_unique<dyncal::replay::Estimator<double, U>>();
  if constexpr (U == Updater::payload) est->set_arm(arm);
  auto diff = std::make_unique<dyncal::CausalDifferentiator<double, 6>>();
  if (est->reset() != dyncal::UpdateStatus::ok) throw std::runtime_error("reset failed");
  c = dyncal::replay::run(*est, *diff, reinterpret_cast<const float(*)[12]>(samples.data()),
                          static_cast<int>(samples.size()), 1.0 / kRate, sigma, [](int) {});
  return std::vector<double>(est->estimate().data(), est->estimate().data() + est->estimate().size());
}

void write_array(std::ostream& o, const char* name, const std::vector<double>& v) {
  o << "inline constexpr double " << name << "[" << v.size() << "] = {";
  for (size_t i = 0; i < v.size(); ++i) o << (i % 4 == 0 ? "\n    " : " ") << std::setprecision(17) << v[i] << ",";
  o << "};\n";
}

/// Every updater's double replay of `samples`: the header's comment line on the accepted updates
/// and its reference arrays (from "/// Host double-precision" to the end of the file).
struct References {
  std::string accepted_line, arrays;
};

References references(const std::vector<std::array<float, 12>>& samples, const double* sigma) {
  dyncal::replay::Counts ck, cr, ce, cf, cp;
  const auto kf = reference<Updater::kf>(samples, sigma, ck);
  const auto rls = reference<Updater::rls>(samples, sigma, cr);
  const auto ekf = reference<Updater::ekf>(samples, sigma, ce);
  const auto friction = reference<Updater::friction>(samples, sigma, cf);
  const auto payload = reference<Updater::payload>(samples, sigma, cp, kf.data());
  References r;
  std::ostringstream a, o;
  a << "// (accepted updates: KF " << ck.accepted << ", RLS " << cr.accepted << ", EKF " << ce.accepted
    << ", friction tracker " << cf.accepted << ", payload " << cp.accepted << ").\n";
  r.accepted_line = a.str();
  o << "/// Host double-precision estimates after the replay (parameter order of replay.hpp).\n";
  write_array(o, "kReferenceKf", kf);
  write_array(o, "kReferenceRls", rls);
  write_array(o, "kReferenceEkf", ekf);
  write_array(o, "kReferenceFriction", friction);
  write_array(o, "kReferencePayload", payload);
  o << "\n}  // namespace dyncal::replay::data\n// clang-format on\n";
  r.arrays = o.str();
  return r;
}

/// --references: the committed recording's references computed again (a new updater, a changed
/// one), its samples and comments kept: the header at `path` rewritten from its accepted-updates
/// line on.
void rewrite_references(const char* path) {
  std::vector<std::array<float, 12>> samples(static_cast<size_t>(dyncal::replay::data::kCount));
  for (int k = 0; k < dyncal::replay::data::kCount; ++k)
    for (int i = 0; i < 12; ++i)
      samples[static_cast<size_t>(k)][static_cast<size_t>(i)] = dyncal::replay::data::kSamples[k][i];
  const References r = references(samples, dyncal::replay::data::kSigma);
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  std::string s = text.str();
  const size_t line = s.find("// (accepted updates:");
  const size_t arrays = s.find("/// Host double-precision estimates");
  if (!in || line == std::string::npos || arrays == std::string::npos)
    throw std::runtime_error(std::string(path) + " is not a replay recording");
  s = s.substr(0, line) + r.accepted_line + s.substr(s.find('\n', line) + 1, arrays - s.find('\n', line) - 1) +
      r.arrays;
  std::ofstream f(path);
  f << s;
  if (!f) throw std::runtime_error(std::string("cannot write ") + path);
}

/// The er20's ratings (robot.json's limits, tau_max derived when the file gives none) as float arrays.
void write_ratings(const char* path) {
  dyncal::host::RobotDescription robot = dyncal::host::load_robot(dyncal::host::default_robots_dir(), "er20");
  dyncal::host::derive_tau_max(robot);
  std::ostringstream o;
  o << "// GENERATED FILE - DO NOT EDIT.\n"
    << "// Generator: host_sim/tools/replay_data.cpp --ratings (cmake --build <build> --target replay-data)\n"
    << "// Input: robots/er20/robot.json (limits, joint side), robots/er20/drive.json (the simulated arm).\n"
    << "#pragma once\n\n// clang-format off\nnamespace dyncal::replay::data {\n\n"
    << "/// The er20's ratings: tau_max [Nm], qd_max [rad/s], qdd_max [rad/s^2], q_min, q_max [rad]; the\n"
    << "/// parameter store's table plausibility (dyncal/table_check.hpp JointRatings).\n";
  const std::pair<const char*, const Eigen::VectorXd*> ratings[] = {{"kTauMax", &robot.tau_max},
                                                                    {"kQdMax", &robot.qd_max},
                                                                    {"kQddMax", &robot.qdd_max},
                                                                    {"kQMin", &robot.q_min},
                                                                    {"kQMax", &robot.q_max}};
  for (const auto& [name, v] : ratings) {
    o << "inline constexpr float " << name << "[6] = {";
    for (int j = 0; j < 6; ++j)
      o << std::showpoint << std::setprecision(9) << static_cast<float>((*v)[j]) << "f" << (j < 5 ? ", " : "};\n");
  }
  // The arm the drive image simulates: the host simulated drive's default scenario of the robot
  // (scenario.hpp default_scenario), which is the one every calibrate test of the er20 runs.
  const dyncal::host::Scenario sc = dyncal::host::default_scenario(robot);
  for (int m = 0; m < 6; ++m)
    for (int k = 0; k < 6; ++k)
      if (sc.motor_map[static_cast<size_t>(m)][static_cast<size_t>(k)] != (m == k ? 1.0 : 0.0))
        throw std::runtime_error("the drive image simulates one motor per joint; the er20 couples motors");
  Eigen::VectorXd fc(6), beta(6), ia(6), noise(6), quantum(6);
  for (int j = 0; j < 6; ++j) {
    if (sc.friction[j].model != dyncal::host::FrictionModel::eq7)
      throw std::runtime_error("the drive image simulates Eq. 7 friction");
    fc[j] = sc.friction[j].Fc;
    beta[j] = sc.friction[j].beta;
    ia[j] = sc.effects[j].rotor_inertia;
    noise[j] = sc.tau_noise_std[j];
    quantum[j] = 2.0 * M_PI / (sc.encoder_counts * std::fabs(robot.gear_ratios[j]));
  }
  o << "\n/// The arm the drive image simulates (port/cortex_m/app/simulated_arm.hpp): the host simulated\n"
    << "/// drive's default scenario of the er20 (robots/er20/robot.json, drive.json). Eq. 7 friction Fc [Nm],\n"
    << "/// beta [Nm s/rad]; reflected rotor inertia J_m N^2 [kg m^2]; torque measurement noise std [Nm];\n"
    << "/// encoder quantum on the joint side 2 pi / (counts N) [rad].\n";
  const std::pair<const char*, const Eigen::VectorXd*> arm[] = {
      {"kCoulomb", &fc}, {"kViscous", &beta}, {"kRotorInertia", &ia}, {"kTauNoiseStd", &noise}, {"kQuantum", &quantum}};
  for (const auto& [name, v] : arm) {
    o << "inline constexpr double " << name << "[6] = {";
    for (int j = 0; j < 6; ++j) o << std::setprecision(17) << (*v)[j] << (j < 5 ? ", " : "};\n");
  }
  o << "/// The control loop: rate [Hz], RK4 substeps per period, PD natural frequency [Hz] and damping.\n"
    << "inline constexpr double kControlRateHz = " << sc.control_rate_hz << ";\n"
    << "inline constexpr int kSubsteps = " << sc.substeps << ";\n"
    << "inline constexpr double kBandwidthHz = " << sc.bandwidth_hz << ";\n"
    << "inline constexpr double kDamping = " << sc.damping << ";\n";
  o << "\n}  // namespace dyncal::replay::data\n// clang-format on\n";
  std::ofstream f(path);
  f << o.str();
  if (!f) throw std::runtime_error(std::string("cannot write ") + path);
}

/// The recording: the er20's simulated drive (its default scenario with Eq. 4 friction, seed kSeed,
/// kRate) playing two periods of the default excitation; q[6] and tau[6] per sample. `scenario`
/// receives the drive's scenario, `cond` the excitation's cond(K). Throws std::runtime_error when
/// the drive faults.
std::vector<std::array<float, 12>> recorded_samples(dyncal::host::Scenario& scenario, double& cond) {
  const auto robot = dyncal::host::load_robot(dyncal::host::default_robots_dir(), "er20");
  scenario = dyncal::host::default_scenario(robot);
  scenario.seed = kSeed;
  scenario.sample_rate_hz = kRate;
  for (int j = 0; j < 6; ++j) {
    scenario.friction[j].model = dyncal::host::FrictionModel::eq4;  // Fc, Fs, qds, beta of robot.json
    scenario.effects[j].rotor_inertia = 0.0;                        // the replayed models declare none
  }
  const auto traj = dyncal::host::default_excitation(robot, 0.1, 5, 16, kSeed, &cond);
  const std::string table = (std::filesystem::temp_directory_path() / "dyncal_replay_table.bin").string();
  std::filesystem::remove(table);
  dyncal::host::SimulatedDrive drive(robot, scenario, table);
  for (int j = 0; j < 6; ++j) {
    for (int l = 0; l < dyncal::modbus_map::kMaxHarmonics; ++l) {
      drive.trajectory.a(j, l) = traj.a(j, l);
      drive.trajectory.b(j, l) = traj.b(j, l);
    }
    drive.trajectory.q0[j] = traj.q0[j];
  }
  drive.trajectory.f_f = traj.f_f;
  drive.trajectory.harmonics = traj.harmonics;
  drive.periods = 2;
  drive.sample_rate_hz = kRate;
  drive.start();
  std::vector<std::array<float, 12>> samples;
  while (drive.state() == dyncal::modbus_map::DriveState::playing) {
    drive.step();
    for (const auto& s : drive.ring()) {
      std::array<float, 12> row{};
      for (int j = 0; j < 6; ++j) {
        row[j] = s.q[j];
        row[6 + j] = s.tau[j];
      }
      samples.push_back(row);
    }
    if (!drive.ring().empty()) drive.ack(drive.ring().back().seq + 1);
  }
  std::filesystem::remove(table);
  if (drive.state() == dyncal::modbus_map::DriveState::fault)
    throw std::runtime_error("the simulated drive stopped: joint " + std::to_string(drive.fault_joint()) + " " +
                             dyncal::modbus_map::to_string(drive.fault()));
  return samples;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::string(argv[1]) == "--ratings") {
    try {
      write_ratings(argv[2]);
      return 0;
    } catch (const std::exception& e) {
      std::cerr << "dyncal_replay_data: " << e.what() << "\n";
      return 1;
    }
  }
  if (argc == 3 && std::string(argv[1]) == "--references") {
    try {
      rewrite_references(argv[2]);
      return 0;
    } catch (const std::exception& e) {
      std::cerr << "dyncal_replay_data: " << e.what() << "\n";
      return 1;
    }
  }
  if (argc != 2) {
    std::cerr << "usage: dyncal_replay_data OUT.hpp | --ratings OUT.hpp | --references DATA.hpp\n";
    return 2;
  }
  try {
    double cond = 0;
    dyncal::host::Scenario scenario;
    const std::vector<std::array<float, 12>> samples = recorded_samples(scenario, cond);
    const double* sigma = scenario.tau_noise_std.data();
    const References refs = references(samples, sigma);

    std::ostringstream o;
    o << "// GENERATED FILE - DO NOT EDIT.\n"
      << "// Generator: host_sim/tools/replay_data.cpp (cmake --build <build> --target replay-data)\n"
      << "// A recording: the simulated drive as it was when this file was written (git log dates it);\n"
      << "// recording again after the simulator changed gives other samples. What must hold is that the\n"
      << "// references below are the replay of these samples: FirmwareReplay checks it on every test run.\n"
      << "// Inputs: robots/er20, the simulated drive (seed " << kSeed << ", Eq. 4 friction from robot.json, survey\n"
      << "// Table 7 torque noise, encoder quantisation), default excitation (cond(K) " << std::setprecision(4) << cond
      << "), " << kRate << " Hz, 2 periods.\n"
      << "// Reference estimates: port/replay/replay.hpp run in double on the host\n"
      << refs.accepted_line << "#pragma once\n\n// clang-format off\nnamespace dyncal::replay::data {\n\n"
      << "inline constexpr double kSamplePeriod = " << 1.0 / kRate << ";  // [s]\n"
      << "/// Torque noise standard deviation per joint [Nm] (survey Table 7): R = sigma^2.\n"
      << "inline constexpr double kSigma[6] = {";
    for (int j = 0; j < 6; ++j) o << std::setprecision(17) << sigma[j] << (j < 5 ? ", " : "};\n");
    o << "inline constexpr int kCount = " << samples.size() << ";\n"
      << "/// Drive samples: q[6] [rad], tau[6] [Nm] (float32, as the drive records them).\n"
      << "inline constexpr float kSamples[kCount][12] = {\n";
    for (const auto& row : samples) {
      o << "    {";
      for (int i = 0; i < 12; ++i) o << std::setprecision(9) << row[i] << "f" << (i < 11 ? ", " : "},\n");
    }
    o << "};\n\n" << refs.arrays;
    std::ofstream f(argv[1]);
    f << o.str();
    if (!f) throw std::runtime_error(std::string("cannot write ") + argv[1]);
    std::cerr << "wrote " << argv[1] << ": " << samples.size() << " samples; " << refs.accepted_line;
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "dyncal_replay_data: " << e.what() << "\n";
    return 1;
  }
}
