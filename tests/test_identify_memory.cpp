// Peak memory of `dyncal identify` against the log's numeric size (issue 23: at most 3x the log,
// rows x columns x 8 bytes, plus a constant). The constant (program, robot model, libraries) is
// measured, not assumed: the peak of the same run on a log a tenth as long.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "support/simulated_log.hpp"

namespace dyncal::test {
namespace {

/// Peak resident set [bytes] of `dyncal ARGS` run as a child (wait4's ru_maxrss); -1 if it failed.
long peak_rss_of_dyncal(const std::vector<std::string>& args) {
  std::vector<char*> argv{const_cast<char*>(DYNCAL_BINARY)};
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    if (!freopen("/dev/null", "w", stdout)) _exit(127);
    execv(DYNCAL_BINARY, argv.data());
    _exit(127);
  }
  int status = 0;
  rusage usage{};
  if (pid < 0 || wait4(pid, &status, 0, &usage) != pid || !WIFEXITED(status) || WEXITSTATUS(status) != 0) return -1;
  return usage.ru_maxrss * 1024L;
}

/// A simulated 1 kHz log of arm6 lasting `seconds`, as a CSV of t, q1..6, tau1..6; its numeric
/// size [bytes] into *numeric.
std::string write_log(const std::filesystem::path& dir, double seconds, double* numeric) {
  const RobotDescription robot = test_robot("arm6");
  const SimulatedLog s = simulate(robot, uniform_times(1000.0, seconds), MotionClock{}, 7);
  const std::string path = (dir / ("log_" + std::to_string(static_cast<int>(seconds)) + "s.csv")).string();
  host::write_csv_log(path, s.log);
  *numeric = static_cast<double>(s.log.samples()) * (1 + 2 * robot.num_joints) * 8.0;
  return path;
}

TEST(IdentifyMemory, PeakIsAtMostThreeTimesTheLogPlusAConstant) {
  const auto dir = std::filesystem::temp_directory_path() / ("dyncal_memory_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  double small_size = 0, large_size = 0;
  const std::string small = write_log(dir, 20.0, &small_size);
  const std::string large = write_log(dir, 200.0, &large_size);
  const std::vector<std::string> common{"identify", "--robots-dir", std::string(DYNCAL_SOURCE_DIR) + "/tests/robots",
                                        "--robot",  "arm6",         "--model",
                                        "eq7",      "--data"};
  std::vector<std::string> a = common, b = common;
  a.push_back(small);
  b.push_back(large);
  const long small_peak = peak_rss_of_dyncal(a), large_peak = peak_rss_of_dyncal(b);
  std::filesystem::remove_all(dir);
  ASSERT_GT(small_peak, 0) << "identify failed on the short log";
  ASSERT_GT(large_peak, 0) << "identify failed on the long log";
  // The constant is what the short run needs beyond its own 3x allowance, at most its peak.
  const double allowance = 3.0 * (large_size - small_size);
  std::printf("peak RSS: %.1f MB on a %.1f MB log, %.1f MB on a %.1f MB log: %.2fx the difference in size\n",
              small_peak / 1e6, small_size / 1e6, large_peak / 1e6, large_size / 1e6,
              static_cast<double>(large_peak - small_peak) / (large_size - small_size));
  EXPECT_LE(static_cast<double>(large_peak - small_peak), allowance);
}

}  // namespace
}  // namespace dyncal::test
