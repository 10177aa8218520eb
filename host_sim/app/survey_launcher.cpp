// dyncal survey: runs the program dyncal-survey beside dyncal with the same arguments
// (commands.hpp, add_survey_launcher).
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "dyncal_host/common/input_error.hpp"

namespace dyncal::app {
namespace {

int launch_survey(const std::vector<std::string>& args) {
  std::error_code ec;
  const std::filesystem::path self = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) throw host::InputError("survey: cannot find the running program (/proc/self/exe): " + ec.message());
  const std::filesystem::path program = self.parent_path() / "dyncal-survey";
  if (::access(program.c_str(), X_OK) != 0) {
    throw host::InputError("survey: the study is the program dyncal-survey, which is not built beside " +
                           self.string() + ": build it with `scripts/build dyncal-survey`");
  }
  std::vector<std::string> argv_strings{"dyncal", "survey"};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (auto& a : argv_strings) argv.push_back(a.data());
  argv.push_back(nullptr);
  ::execv(program.c_str(), argv.data());
  throw host::InputError("survey: cannot run " + program.string() + ": " + std::strerror(errno));
}

}  // namespace

void add_survey_launcher(CLI::App& app, Action& run) {
  auto* cmd = app.add_subcommand("survey", kSurveyHelp);
  // Every argument, --help included, is the study's (dyncal-survey parses them).
  cmd->set_help_flag();
  cmd->prefix_command();
  cmd->allow_extras();
  cmd->callback([&run, cmd] {
    const std::vector<std::string> args = cmd->remaining();
    run = [args] { return launch_survey(args); };
  });
}

}  // namespace dyncal::app
