// `dyncal identify` and `dyncal calibrate --trajectory` on malformed input: one clear line on
// stderr naming the problem, exit code 2; `dyncal excite` writes a file calibrate accepts.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

struct Run {
  int exit_code;
  std::string err;
};

Run run_dyncal(const std::string& args) {
  const std::string err_file = std::filesystem::temp_directory_path() / ("dyncal_err_" + std::to_string(::getpid()));
  const std::string cmd = std::string(DYNCAL_BINARY) + " " + args + " >/dev/null 2>" + err_file;
  const int status = std::system(cmd.c_str());
  std::ifstream in(err_file);
  std::string err((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::filesystem::remove(err_file);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, err};
}

std::string write_csv(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("dyncal_test_" + name + ".csv");
  std::ofstream(path) << text;
  return path.string();
}

std::string header(int joints, bool with_t = true) {
  std::string h = with_t ? "t" : "time";
  for (int j = 1; j <= joints; ++j) h += ",q" + std::to_string(j);
  for (int j = 1; j <= joints; ++j) h += ",tau" + std::to_string(j);
  return h + "\n";
}

std::string rows(int joints, int count, double dt = 0.01) {
  std::string s;
  for (int i = 0; i < count; ++i) {
    s += std::to_string(i * dt);
    for (int j = 0; j < 2 * joints; ++j) s += "," + std::to_string(0.1 * j + 0.01 * i);
    s += "\n";
  }
  return s;
}

void expect_error(const std::string& args, const std::string& needle) {
  const Run r = run_dyncal(args);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(needle), std::string::npos) << "stderr: " << r.err;
  EXPECT_EQ(std::count(r.err.begin(), r.err.end(), '\n'), 1) << "one line expected: " << r.err;
}

TEST(CliErrors, MissingColumn) {
  std::string text = "t,q1,q2,q3,q4,q5,q6,tau1,tau2,tau3,tau4,tau5\n";
  for (int i = 0; i < 10; ++i) text += std::to_string(0.01 * i) + ",1,2,3,4,5,6,1,2,3,4,5\n";
  expect_error("identify --robot er20 --data " + write_csv("missing", text), "missing column 'tau6'");
}

TEST(CliErrors, NaNValue) {
  const std::string text = header(6) + rows(6, 5) + "0.05,1,2,nan,4,5,6,1,2,3,4,5,6\n";
  expect_error("identify --robot er20 --data " + write_csv("nan", text), "non-finite value");
}

TEST(CliErrors, NonNumericValue) {
  std::string text = header(6) + rows(6, 5) + "0.05,1,2,3,4,5,x,1,2,3,4,5,6\n";
  expect_error("identify --robot er20 --data " + write_csv("text", text), "'x' is not a number");
}

TEST(CliErrors, NonMonotonicTime) {
  std::string text = header(6) + rows(6, 5) + rows(6, 5);
  expect_error("identify --robot er20 --data " + write_csv("time", text), "time is not strictly increasing");
}

TEST(CliErrors, WrongJointCount) {
  expect_error("identify --robot er20 --data " + write_csv("joints", header(5) + rows(5, 10)), "5 joints");
}

TEST(CliErrors, UnknownRobot) {
  expect_error("identify --robot nosuch --data " + write_csv("robot", header(6) + rows(6, 10)),
               "unknown robot 'nosuch'");
}

TEST(CliErrors, MissingTimeColumn) {
  expect_error("identify --robot er20 --data " + write_csv("not", header(6, false) + rows(6, 10)),
               "missing column 't'");
}

// A command-line value outside its set: CLI11's message (which adds a --help hint line), exit 2.
TEST(CliErrors, UnknownSurveyPriorIsRefusedBeforeAnyRun) {
  const auto r = run_dyncal("survey --prior-on cad");
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--prior-on"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("cad"), std::string::npos) << r.err;
}

// Where calibrate would write its logs is checked before any drive is contacted (the URI below
// serves nothing): a run must not stream for minutes and then lose its samples.
TEST(CliErrors, CalibrateLogDirectoriesAreCheckedBeforeTheDrive) {
  expect_error("calibrate --drive tcp://127.0.0.1:1 --fault-dir /nonexistent", "fault directory '/nonexistent'");
  expect_error("calibrate --drive tcp://127.0.0.1:1 --save-log /nonexistent/x.csv", "no directory '/nonexistent'");
}

TEST(CliErrors, MissingFile) {
  expect_error("identify --robot er20 --data /nonexistent/log.csv", "cannot read");
}

// The trajectory file is checked before any drive is contacted (the URI below serves nothing).
TEST(CliErrors, TrajectoryFileBeyondALimitIsRefused) {
  const auto path = std::filesystem::temp_directory_path() / ("dyncal_test_traj_" + std::to_string(::getpid()));
  // Joint 2 at 50 rad/s: beyond its position range and velocity limit (2.97 rad/s).
  std::ofstream(path) << R"({"robot": "er20", "f_f": 0.1, "harmonics": 1, "q0": [0, 0, 0, 0, 0, 0],
    "a": [[0.1], [50], [0.1], [0.1], [0.1], [0.1]], "b": [[0], [0], [0], [0], [0], [0]]})";
  expect_error("calibrate --drive tcp://127.0.0.1:1 --trajectory " + path.string(), "joint 2 exceeds its");
  expect_error("calibrate --drive tcp://127.0.0.1:1 --trajectory /nonexistent/t.json", "cannot read");
  // A designed file passes the check: the error is then the missing drive.
  const auto made = run_dyncal("excite --evaluations 20 --out " + path.string());
  ASSERT_EQ(made.exit_code, 0) << made.err;
  const auto played = run_dyncal("calibrate --drive tcp://127.0.0.1:1 --trajectory " + path.string());
  EXPECT_EQ(played.exit_code, 2);
  EXPECT_EQ(played.err.find("trajectory"), std::string::npos) << played.err;
  std::filesystem::remove(path);
}

}  // namespace
