#pragma once
// Gates for an end-of-line calibration station (docs/gates.md): thresholds in, a verdict out. A gate
// is evaluated on a command's JSON report (the numbers --report writes), so the verdict is the
// report's own numbers against the station's limits; the items and the verdict join the report
// ("gate") and the command exits 1 when an item fails.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "dyncal_host/common/normal_quantile.hpp"  // kZ95: the pages' intervals, the physics gate's bound

namespace dyncal::host {

/// One limit: a key the command knows (gate_keys) and one value, or one per joint.
struct GateLimit {
  std::string key;
  std::vector<double> values;  ///< one value for every joint or the report, or one per joint
  std::string source;          ///< where it was set: the gate file, or --require
};

/// The limits of one command.
struct Gate {
  std::string command;  ///< identify, predict, diagnose, payload, monitor, calibrate
  std::vector<GateLimit> limits;
  bool empty() const { return limits.empty(); }
};

/// One checked item.
struct GateItem {
  std::string key;
  int joint = 0;      ///< 1-based; 0 when the item is not a joint's
  std::string what;   ///< the checked quantity in words, e.g. "joint 2 cross-validated R^2"
  double value = 0;   ///< the report's number (NaN: the report has none)
  double limit = 0;   ///< the gate's bound
  std::string bound;  ///< ">=" or "<="
  bool passed = false;
};

struct GateResult {
  bool passed = true;
  std::vector<GateItem> items;
};

/// The keys `command` knows, with their meaning (docs/gates.md lists the same).
std::vector<std::pair<std::string, std::string>> gate_keys(const std::string& command);

/// The gate of `command` from a gate file (YAML, or JSON which is YAML: a map with a section per
/// command, each a map of key: number, key: [per-joint numbers], or key: true) and --require items
/// ("key=value" or "key=v1,v2,..."), which add to or replace the file's. Either may be empty. Throws
/// InputError (one line): the file unreadable or not such a map, no section for `command` when the
/// file is given, a key the command does not know (the known ones listed), a value that is not a
/// finite number.
Gate read_gate(const std::string& command, const std::string& gate_file, const std::vector<std::string>& require);

/// The gate's items on `report` (the command's JSON report). A limit per joint must list as many
/// values as the report has joints (InputError otherwise). A quantity the report lacks (e.g. link
/// masses of a method that has none) fails its item with value NaN: a station never passes on a
/// number it does not have.
GateResult evaluate_gate(const Gate& gate, const nlohmann::json& report);

/// {"passed", "items": [{key, joint, what, value, limit, bound, passed}]} (value null when NaN).
nlohmann::json gate_json(const GateResult& r);

/// The verdict as text: one line "gate: passed (K items)" or "gate: FAILED (F of K items)" followed by
/// each failed item on its own line.
std::string gate_text(const GateResult& r);

}  // namespace dyncal::host
