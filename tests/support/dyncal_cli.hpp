#pragma once
// Running the dyncal command line from a test and reading the JSON it writes.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "support/test_paths.hpp"

namespace dyncal::test {

/// Runs `dyncal ARGS` (dyncal_binary()) with its output discarded; its exit code, -1 if it did not exit.
inline int run_dyncal(const std::string& args) {
  const int status =
      std::system((std::string(dyncal::test::dyncal_binary()) + " " + args + " >/dev/null 2>&1").c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// The JSON document of a file dyncal wrote.
inline nlohmann::json read_json(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

}  // namespace dyncal::test
