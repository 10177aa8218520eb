#include "dyncal_host/logs/merged_files.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/logs/numeric_csv.hpp"

namespace dyncal::host {
namespace {

/// One file: its times and columns by name.
struct TimedFile {
  std::string path;
  NumericCsv csv;
  std::map<std::string, Eigen::Index> col;
  Eigen::VectorXd t;
  double median_period = 0;
};

/// The columns of `names` in `f`, or nothing when it lacks any.
std::optional<std::vector<Eigen::Index>> columns_of(const TimedFile& f, const std::vector<std::string>& names) {
  std::vector<Eigen::Index> out;
  for (const std::string& n : names) {
    const auto it = f.col.find(n);
    if (it == f.col.end()) return std::nullopt;
    out.push_back(it->second);
  }
  return out;
}

struct Source {
  const TimedFile* file = nullptr;
  std::vector<Eigen::Index> columns;
};

}  // namespace

ColumnMap default_column_map(const std::vector<bool>& prismatic, bool current) {
  const int joints = static_cast<int>(prismatic.size());
  ColumnMap m;
  m.prismatic = prismatic;
  m.t = "t";
  for (int j = 1; j <= joints; ++j) {
    const std::string k = std::to_string(j);
    m.q.push_back("q" + k);
    m.qd.push_back("qd" + k);
    m.qdd.push_back("qdd" + k);
    m.effort.push_back((current ? "i" : "tau") + k);
  }
  m.effort_is_current = current;
  m.origin = "merged files";
  return m;
}

namespace {

/// The file at `path` with its time column (map.t, scaled; else the first) checked and its median period.
void read_timed_file(const std::string& path, const ColumnMap& map, TimedFile& f) {
  f.path = path;
  f.csv = read_numeric_csv(f.path);
  f.col = column_index(f.csv, f.path);
  const auto t = f.col.find(map.t);
  f.t = map.t_scale * f.csv.values.col(t != f.col.end() ? t->second : 0);
  check_log_time(f.t, f.path);
  std::vector<double> dt(static_cast<size_t>(f.t.size() - 1));
  for (Eigen::Index i = 1; i < f.t.size(); ++i) dt[static_cast<size_t>(i - 1)] = f.t[i] - f.t[i - 1];
  std::nth_element(dt.begin(), dt.begin() + static_cast<long>(dt.size() / 2), dt.end());
  f.median_period = dt[dt.size() / 2];
}

/// The rows of `grid` (q's stamps, from q_file) that every other source's file covers without a
/// gap (a step over twice its median period); the stamps left out counted in outside / across.
std::vector<Eigen::Index> covered_stamps(const Eigen::VectorXd& grid, const TimedFile* q_file,
                                         std::initializer_list<const Source*> others, long& outside, long& across) {
  std::vector<Eigen::Index> kept;
  for (Eigen::Index i = 0; i < grid.size(); ++i) {
    bool ok = true;
    for (const Source* s : others) {
      if (!s->file || s->file == q_file) continue;
      const Eigen::VectorXd& t = s->file->t;
      if (grid[i] < t[0] || grid[i] > t[t.size() - 1]) {
        ok = false, ++outside;
        break;
      }
      const auto hi = std::lower_bound(t.data(), t.data() + t.size(), grid[i]) - t.data();
      if (hi > 0 && t[hi] != grid[i] && t[hi] - t[hi - 1] > 2.0 * s->file->median_period) {
        ok = false, ++across;
        break;
      }
    }
    if (ok) kept.push_back(i);
  }
  return kept;
}

}  // namespace

JointLog read_merged_csv_logs(const std::vector<std::string>& paths, const ColumnMap& map, int joints,
                              std::vector<std::string>* notes) {
  std::vector<TimedFile> files(paths.size());
  for (size_t k = 0; k < paths.size(); ++k) read_timed_file(paths[k], map, files[k]);
  // Each signal from the one file that holds all its columns.
  const auto find = [&](const std::vector<std::string>& names, const char* what, bool required) {
    Source s;
    if (names.empty()) return s;
    for (const TimedFile& f : files) {
      const auto c = columns_of(f, names);
      if (!c) continue;
      if (s.file)
        throw InputError(std::string(what) + " (" + names.front() + "..) is in both " + s.file->path + " and " +
                         f.path + ": give each signal once");
      s = {&f, *c};
    }
    if (!s.file && required)
      throw InputError(std::string("no file of --data holds ") + what + " (columns " + names.front() + ".." +
                       names.back() + ", " + map.origin + ")");
    return s;
  };
  const Source q = find(map.q, "q", true), effort = find(map.effort, "the effort", true);
  const Source qd = find(map.qd, "qd", false), qdd = find(map.qdd, "qdd", false);
  for (const TimedFile& f : files)
    if (q.file != &f && effort.file != &f && qd.file != &f && qdd.file != &f)
      throw InputError(f.path + ": holds none of the log's signals (" + map.origin + ")");

  // The samples: q's stamps that every other file covers without a gap.
  const Eigen::VectorXd& grid = q.file->t;
  long outside = 0, across = 0;
  const std::vector<Eigen::Index> kept = covered_stamps(grid, q.file, {&effort, &qd, &qdd}, outside, across);
  const auto S = static_cast<Eigen::Index>(kept.size());
  if (S < 3)
    throw InputError("the files of --data share fewer than 3 samples in time (" + q.file->path +
                     "'s stamps within the others' spans)");
  // A signal at the kept stamps: its own rows, or interpolated linearly in its file.
  const auto at_stamps = [&](const Source& s, double angular_scale, double linear_scale) {
    Eigen::MatrixXd m(S, joints);
    const Eigen::VectorXd& t = s.file->t;
    for (Eigen::Index r = 0; r < S; ++r) {
      const double x = grid[kept[static_cast<size_t>(r)]];
      Eigen::Index hi = s.file == q.file ? kept[static_cast<size_t>(r)]
                                         : std::lower_bound(t.data(), t.data() + t.size(), x) - t.data();
      const Eigen::Index lo = t[hi] == x ? hi : hi - 1;
      const double w = hi == lo ? 0.0 : (x - t[lo]) / (t[hi] - t[lo]);
      for (int j = 0; j < joints; ++j) {
        const Eigen::Index c = s.columns[static_cast<size_t>(j)];
        m(r, j) = map.joint_scale(j, angular_scale, linear_scale) *
                  ((1.0 - w) * s.file->csv.values(lo, c) + w * s.file->csv.values(hi, c));
      }
    }
    return m;
  };
  JointLog log;
  log.t.resize(S);
  for (Eigen::Index r = 0; r < S; ++r) log.t[r] = grid[kept[static_cast<size_t>(r)]];
  log.q = at_stamps(q, map.q_scale, map.q_linear_scale);
  log.tau = at_stamps(effort, map.effort_scale, map.force_scale);
  log.has_qd = qd.file != nullptr;
  log.has_qdd = qdd.file != nullptr;
  if (log.has_qd) log.qd = at_stamps(qd, map.qd_scale, map.qd_linear_scale);
  if (log.has_qdd) log.qdd = at_stamps(qdd, map.qdd_scale, map.qdd_linear_scale);
  std::string source;
  for (const std::string& p : paths) source += (source.empty() ? "" : " + ") + p;
  log.source = source + " (merged on time)";
  if (notes) {
    std::string line =
        "merged on time: q from " + q.file->path + " (its " + std::to_string(grid.size()) + " stamps are the log's)";
    for (const auto& [s, what] : {std::pair<const Source*, const char*>{&qd, "qd"}, {&qdd, "qdd"}, {&effort, "effort"}})
      if (s->file) line += std::string(", ") + what + " from " + s->file->path + (s->file == q.file ? "" : " (linear)");
    if (outside + across > 0)
      line += "; " + std::to_string(outside) + " stamps outside another file's span and " + std::to_string(across) +
              " inside a gap of another file (over twice its median period) left out";
    notes->push_back(line);
  }
  return log;
}

}  // namespace dyncal::host
