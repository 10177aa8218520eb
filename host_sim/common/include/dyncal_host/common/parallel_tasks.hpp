#pragma once
// Independent tasks on several threads (the survey's runs, diagnose's candidates): each task writes
// only its own result slot, so the results are those of a sequential run, bit for bit, whatever the
// thread count.

#include <functional>
#include <string>
#include <vector>

namespace dyncal::host {

/// A unit of work and a relative cost hint (larger: started earlier, so that the longest runs do
/// not end up last on one thread).
struct ParallelTask {
  double cost = 1;
  std::function<void()> run;
};

/// Runs every task on up to `jobs` threads (jobs <= 1: in the calling thread, in order), the costly
/// ones first, reporting each finished task as progress of `what` (progress.hpp; `unit` names the
/// tasks in it). Rethrows the first
/// exception a task threw (by its position in `tasks`) after every task has finished.
void run_parallel(std::vector<ParallelTask> tasks, int jobs, const std::string& what, const std::string& unit = "runs");

/// Threads to use by default: std::thread::hardware_concurrency(), at least 1.
int default_jobs();

}  // namespace dyncal::host
