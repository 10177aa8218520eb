#include "dyncal_host/common/parallel_tasks.hpp"

#include <algorithm>
#include <atomic>
#include <exception>
#include <numeric>
#include <thread>

#include "dyncal_host/common/progress.hpp"

namespace dyncal::host {

void run_parallel(std::vector<ParallelTask> tasks, int jobs, const std::string& what, const std::string& unit) {
  Progress progress(what, static_cast<double>(tasks.size()), unit);
  std::vector<size_t> order(tasks.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return tasks[a].cost > tasks[b].cost; });
  std::vector<std::exception_ptr> errors(tasks.size());
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (size_t i; (i = next.fetch_add(1)) < order.size();) {
      try {
        tasks[order[i]].run();
      } catch (...) {
        errors[order[i]] = std::current_exception();
      }
      progress.advance();
    }
  };
  const size_t threads = std::min(tasks.size(), static_cast<size_t>(std::max(jobs, 1)));
  if (threads <= 1) {
    worker();
  } else {
    std::vector<std::thread> pool;
    for (size_t t = 0; t < threads; ++t) pool.emplace_back(worker);
    for (std::thread& t : pool) t.join();
  }
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

int default_jobs() {
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

}  // namespace dyncal::host
