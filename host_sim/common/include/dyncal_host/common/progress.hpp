#pragma once
// Progress of the long commands (diagnose, the survey, calibrate's runs, identify's folds): a task
// reports how much of it is done to one process-wide sink. None is set by default, so a library
// call (Python's) stays quiet; the dyncal programs set a single updating terminal line when stderr
// is a terminal (terminal_progress), so CI logs and redirected output get nothing; Python's
// dyncal.set_progress(callback) sets the user's function.

#include <functional>
#include <mutex>
#include <ostream>
#include <string>

namespace dyncal::host {

/// One update: the task's name, how much of it is done out of `total` (in `unit`s), and whether it
/// has just finished (then done == total, or less when it ended early).
struct ProgressUpdate {
  std::string task, unit;
  double done = 0, total = 0;
  bool finished = false;
};

using ProgressSink = std::function<void(const ProgressUpdate&)>;

/// Sets the process's sink (an empty function: none). Not to be called while a task runs.
void set_progress_sink(ProgressSink sink);

/// A single line on `out` redrawn in place ("\r"): the task, a bar, the percentage and done/total,
/// first drawn once a task has run 0.25 s (a quick one shows nothing), at most 10 redraws a second,
/// erased when the task finishes. For a terminal only; one task at a time.
ProgressSink terminal_progress(std::ostream& out);

/// One task's progress. Thread-safe: workers of one task may advance it concurrently. The sink is
/// called under a lock, at most once per 1 % of the total (and at the end); nothing happens when no
/// sink is set.
class Progress {
 public:
  Progress(std::string task, double total, std::string unit = "");
  ~Progress();  ///< finishes the task
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  void advance(double n = 1);  ///< n more units done
  void update(double done);    ///< `done` units done in all

 private:
  void report(bool finished);
  ProgressUpdate state_;
  double reported_ = -1;
  std::mutex mutex_;
};

}  // namespace dyncal::host
