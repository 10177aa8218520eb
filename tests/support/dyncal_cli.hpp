#pragma once
// Running the dyncal command line from a test and reading the JSON it writes.
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "support/test_paths.hpp"

namespace dyncal::test {

/// Runs `dyncal ARGS` (dyncal_binary()) with its output discarded; its exit code, -1 if it did not exit.
inline int run_dyncal(const std::string& args) {
  const int status =
      std::system((std::string(dyncal::test::dyncal_binary()) + " " + args + " >/dev/null 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// What a dyncal run printed (stdout and stderr together) and its exit code (-1: it did not exit).
struct CliResult {
  int exit_code = -1;
  std::string output;
};

/// Runs `dyncal ARGS` (dyncal_binary()) with stdout and stderr read into the result.
inline CliResult run_dyncal_captured(const std::string& args) {
  CliResult r;
  FILE* pipe = ::popen((std::string(dyncal::test::dyncal_binary()) + " " + args + " 2>&1").c_str(), "r");
  if (pipe == nullptr) return r;
  char buffer[4096];
  for (size_t got; (got = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;) r.output.append(buffer, got);
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

/// Runs `dyncal ARGS` (dyncal_binary()) as a child with stdout and stderr discarded: its peak
/// resident set [bytes] (wait4's ru_maxrss) and exit code; {-1, -1} if it did not exit.
inline std::pair<long, int> peak_rss_and_exit_code(const std::vector<std::string>& args) {
  std::vector<char*> argv{const_cast<char*>(dyncal_binary())};
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  const pid_t pid = fork();
  if (pid == 0) {
    if (!std::freopen("/dev/null", "w", stdout) || !std::freopen("/dev/null", "w", stderr)) _exit(127);
    execv(dyncal_binary(), argv.data());
    _exit(127);
  }
  int status = 0;
  rusage usage{};
  if (pid < 0 || wait4(pid, &status, 0, &usage) != pid || !WIFEXITED(status)) return {-1, -1};
  return {usage.ru_maxrss * 1024L, WEXITSTATUS(status)};
}

/// The JSON document of a file dyncal wrote.
inline nlohmann::json read_json(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

}  // namespace dyncal::test
