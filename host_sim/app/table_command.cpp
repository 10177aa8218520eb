// dyncal table: the drive's active parameter table, read over Modbus and printed.
#include <iomanip>
#include <iostream>
#include <memory>

#include "commands.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/model_terms.hpp"

namespace dyncal::app {
namespace {

int run_table(const std::string& uri) {
  auto d = connect_drive(uri);
  ParameterTable t;
  TableStatus reason;
  const auto st = d->read(t, &reason);
  if (st == port::PortStatus::transport_error) throw host::InputError("drive: " + d->error());
  if (st != port::PortStatus::ok)
    throw host::InputError(std::string("the drive's table is invalid: ") + to_string(reason));
  std::cout << "active table: robot id 0x" << std::hex << std::setw(8) << std::setfill('0') << t.robot_id << std::dec
            << std::setfill(' ') << ", model " << host::model_name(t.model_id) << " (id " << t.model_id << "), "
            << t.count << " parameters, CRC ok\n";
  for (int i = 0; i < t.count; ++i) std::cout << "  " << std::setw(3) << i + 1 << "  " << t.values[i] << "\n";
  return 0;
}

}  // namespace

void add_table_command(CLI::App& app, Action& run) {
  auto uri = std::make_shared<std::string>("tcp://127.0.0.1:1502");
  auto* cmd = app.add_subcommand("table", "read and print the drive's active parameter table");
  cmd->add_option("--drive", *uri)->capture_default_str();
  cmd->callback([&run, uri] { run = [uri] { return run_table(*uri); }; });
}

}  // namespace dyncal::app
