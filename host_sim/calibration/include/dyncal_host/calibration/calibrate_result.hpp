#pragma once
// What `dyncal calibrate` measured and did (calibrate.hpp).

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "dyncal/modbus_map.hpp"
#include "dyncal/parameter_table.hpp"
#include "dyncal_host/calibration/stream_plan.hpp"
#include "dyncal_host/identification/pipeline/prediction.hpp"
#include "dyncal_host/model/identify_result.hpp"

namespace dyncal::host {

struct VerificationErrors {
  std::array<double, modbus_map::kMaxJoints> rms{};      ///< per joint RMS of tau - K phi on the fresh trajectory [Nm]
  std::array<double, modbus_map::kMaxJoints> rms_tau{};  ///< per joint RMS of tau [Nm]
};

struct CalibrateResult {
  int num_joints = 0;    ///< the robot's; per-joint arrays are filled to here
  IdentifyResult batch;  ///< OLS fit of the excitation run, with cross-validation
  TorqueTrace trace;     ///< with CalibrateOptions::keep_trace: the excitation's torque and the batch fit's prediction
  std::vector<std::string> names;                  ///< parameter names, model order
  std::vector<double> phi_batch, phi_kf, phi_rls;  ///< batch: identify's model; KF, RLS: lib's (per joint)
  double trajectory_cond = 0;                      ///< cond(K) of the chosen excitation (Eq. 26, columns unit-scaled)
  long samples = 0;                                ///< excitation samples streamed
  std::uint32_t lost = 0;                          ///< samples lost to drive overruns (all runs)
  double stream_seconds = 0;                       ///< wall time of the excitation stream
  double samples_per_second = 0;                   ///< streamed samples per wall second
  long online_updates = 0, online_rejected = 0;
  VerificationErrors verify_batch, verify_kf, verify_rls;  ///< fresh trajectory, identified models
  std::array<double, modbus_map::kMaxJoints> drive_error_before{},
      drive_error_after{};           ///< drive's own RMS(tau - tau_ff)
  std::vector<std::string> effects;  ///< explanations of the effects diagnosed and flashed
  std::vector<std::string> effects_not_flashed;
  /// The batch fit's friction and rotor inertia are per motor (robot.json's coupled motors at their
  /// own velocity; the online KF and RLS are lib's per-joint models either way).
  bool friction_per_motor = false;
  std::vector<std::string> table_notes;  ///< how the table holds the batch model (a coupled motor's coupling term)
  /// The drive link: measured before the runs, each run's way over it, and what the runs cost it.
  struct Link {
    std::string transport;           ///< "TCP" or "RTU"
    LinkCapacity capacity;           ///< ModbusDrive::measure_link before the excitation
    std::vector<std::string> plans;  ///< each run's StreamPlan::line, in order
    long transactions = 0;           ///< ring transactions of every run (one per block)
    long bytes = 0;                  ///< their bytes on the wire, both ways
    long samples = 0;                ///< samples received in every run
  } link;
  bool flashed = false;
  TableStatus flash_status = TableStatus::ok;
  std::string flash_message;
  double total_seconds = 0;
};

}  // namespace dyncal::host
