// Running codegen/import_urdf.py from the source tree (commands.hpp: run_urdf_tool).
#include <spawn.h>
#include <sys/wait.h>

#include <string>
#include <vector>

#include "commands.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/source_tree.hpp"

extern char** environ;

namespace dyncal::app {

int run_urdf_tool(const std::vector<std::string>& args) {
  const std::string python = "/usr/bin/python3";
  std::vector<std::string> all{python, host::source_tree_dir() + "/codegen/import_urdf.py"};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  if (posix_spawn(&pid, python.c_str(), nullptr, nullptr, argv.data(), environ) != 0)
    throw host::InputError("cannot run " + python + " (scripts/setup installs it)");
  int status = 0;
  if (waitpid(pid, &status, 0) < 0 || !WIFEXITED(status)) throw host::InputError("the URDF tool did not finish");
  return WEXITSTATUS(status);
}

}  // namespace dyncal::app
