#pragma once
// A log split over several files, each with its own time column (a logger that writes position,
// velocity and effort apart: docs/cli.md "Logs", --merge-on-time), merged into one log on time.

#include <string>
#include <vector>

#include "dyncal_host/logs/column_map.hpp"
#include "dyncal_host/logs/joint_log.hpp"

namespace dyncal::host {

/// The default map of merged files: t, q1..qN, qd1..qN, qdd1..qN and tau1..tauN (or i1..iN with
/// `current`: motor currents, converted afterwards with current_to_joint_torque), in SI units; N =
/// prismatic.size() (per joint: whether it is prismatic, RobotDescription::prismatic).
ColumnMap default_column_map(const std::vector<bool>& prismatic, bool current);

/// Reads `paths` (read_numeric_csv) and merges them on time. Each file's time is its column
/// map.t, else its first column (scaled by map.t_scale); each signal of `map` (q, qd, qdd, effort;
/// all `joints` columns of a signal in one file) is taken from the one file that holds it. The
/// log's samples are the stamps of the file holding q; every other signal is interpolated linearly
/// to them from its file's two neighbouring samples. A stamp outside another file's time span, or
/// between two of its samples more than twice that file's median period apart (a gap it did not
/// record), is left out: a sample is never made up across a gap. `notes` gets one line saying what
/// came from where and what was left out. Throws InputError naming the file: a signal in two files,
/// q or the effort in none, a file with no signal of the map, a time column not strictly
/// increasing, or fewer than 3 samples left.
JointLog read_merged_csv_logs(const std::vector<std::string>& paths, const ColumnMap& map, int joints,
                              std::vector<std::string>* notes);

}  // namespace dyncal::host
