#pragma once
// The allocation counter of test_no_malloc (its main file defines it): malloc, calloc, realloc
// (wrapped at link time, -Wl,--wrap) and operator new count while `counting` is set. Each of the
// program's files defines EIGEN_RUNTIME_NO_MALLOC before any include: Eigen's runtime no-malloc
// check must be compiled into all of them alike.
#ifndef EIGEN_RUNTIME_NO_MALLOC
#error "define EIGEN_RUNTIME_NO_MALLOC before any include"
#endif
#include <Eigen/Core>
#include <atomic>
#include <memory>

namespace dyncal::test {
extern std::atomic<long> allocations;
extern std::atomic<bool> counting;

/// Runs f() with Eigen's no-malloc check on and every allocation counted; returns their number.
template <typename F>
long allocations_during(F&& f) {
  Eigen::internal::set_is_malloc_allowed(false);
  allocations = 0;
  counting = true;
  f();
  counting = false;
  Eigen::internal::set_is_malloc_allowed(true);
  return allocations.load();
}

/// allocations_during run(w) on a double and a float Workspace, both made (on the heap) before
/// counting starts.
template <template <typename> class Workspace, typename Run>
long allocations_in_double_and_float(Run run) {
  auto wd = std::make_unique<Workspace<double>>();
  auto wf = std::make_unique<Workspace<float>>();
  return allocations_during([&] {
    run(*wd);
    run(*wf);
  });
}
}  // namespace dyncal::test
