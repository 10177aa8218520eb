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

#include "dyncal_host/identification/pipeline/kept_samples.hpp"
#include "support/dyncal_cli.hpp"
#include "support/simulated_log.hpp"
#include "support/test_paths.hpp"

namespace dyncal::test {
namespace {

/// Peak resident set [bytes] of `dyncal ARGS` run as a child; -1 if it failed or exited non-zero.
long peak_rss_of_dyncal(const std::vector<std::string>& args) {
  const auto [rss, code] = peak_rss_and_exit_code(args);
  return code == 0 ? rss : -1;
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

/// The peak of `dyncal identify ... extra` on a 200 s log minus its peak on a 20 s log, against 3x
/// the difference in the logs' numeric size.
void expect_peak_within_three_times_the_log(const std::vector<std::string>& extra) {
  const auto dir = std::filesystem::temp_directory_path() / ("dyncal_memory_" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  double small_size = 0, large_size = 0;
  const std::string small = write_log(dir, 20.0, &small_size);
  const std::string large = write_log(dir, 200.0, &large_size);
  std::vector<std::string> common{"identify", "--robots-dir", std::string(dyncal::test::source_dir()) + "/tests/robots",
                                  "--robot",  "arm6",         "--model",
                                  "eq7"};
  common.insert(common.end(), extra.begin(), extra.end());
  common.push_back("--data");
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

TEST(IdentifyMemory, PeakIsAtMostThreeTimesTheLogPlusAConstant) {
  expect_peak_within_three_times_the_log({});
}

// Every sample kept (a log sampled below 50x the cut-off, such as 100 Hz, gets decimation 1): the
// kept signals are as long as the log, so the log's own buffers must be reused, not copied.
TEST(IdentifyMemory, PeakIsAtMostThreeTimesTheLogWithoutDecimation) {
  expect_peak_within_three_times_the_log({"--decimate", "1"});
}

// The kept rows of a log's signal, shrunk in place, against a plain selection into a new matrix:
// several segments (one too short to keep anything), decimation 1 and 3.
TEST(KeptSamples, KeepRowsInPlaceEqualsASelection) {
  for (const Eigen::Index step : {1, 3}) {
    const host::KeptSamples kept{{{0, 40}, {40, 45}, {45, 101}}, 4, step};
    const Eigen::MatrixXd m = Eigen::MatrixXd::Random(101, 5);
    const Eigen::VectorXd t = Eigen::VectorXd::LinSpaced(101, 0.0, 1.0);
    Eigen::MatrixXd want(kept.count(), 5);
    Eigen::VectorXd want_t(kept.count());
    std::vector<Eigen::Index> rows;
    kept.for_each([&](Eigen::Index row, Eigen::Index k) {
      EXPECT_EQ(k, static_cast<Eigen::Index>(rows.size()));
      rows.push_back(row);
      want.row(k) = m.row(row);
      want_t[k] = t[row];
    });
    // Segment [a, b) keeps a + 4, a + 4 + step, ... below b - 4; [40, 45) keeps nothing.
    EXPECT_EQ(rows.front(), 4);
    EXPECT_EQ(kept.count(40, 45), 0);
    EXPECT_EQ(kept.count(), (32 + step - 1) / step + (48 + step - 1) / step);
    Eigen::MatrixXd got = m;
    Eigen::VectorXd got_t = t;
    host::keep_rows_in_place(got, kept);
    host::keep_rows_in_place(got_t, kept);
    ASSERT_EQ(got.rows(), kept.count());
    ASSERT_EQ(got.cols(), 5);
    EXPECT_EQ(got, want) << "step " << step;
    EXPECT_EQ(got_t, want_t) << "step " << step;
  }
}

}  // namespace
}  // namespace dyncal::test
