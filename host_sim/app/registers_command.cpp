// dyncal registers: the Modbus register map as a Markdown table (docs/modbus.md is checked against it).
#include <iostream>

#include "commands.hpp"
#include "dyncal/modbus_map.hpp"

namespace dyncal::app {
namespace {

namespace mm = dyncal::modbus_map;

const char* type_name(mm::Type t) {
  switch (t) {
    case mm::Type::u16:
      return "u16";
    case mm::Type::u32:
      return "u32";
    case mm::Type::f32:
      return "f32";
    case mm::Type::bytes:
      return "bytes";
  }
  return "?";
}

int run_registers() {
  std::cout << "| name | bank | address | registers | type | unit | description |\n|---|---|---|---|---|---|---|\n";
  for (const auto& f : mm::kRegisterMap) {
    std::cout << "| `" << f.name << "` | "
              << (f.bank == mm::Bank::input  ? "input (04, read)"
                  : mm::read_only_holding(f) ? "holding (03/23, read-only)"
                                             : "holding (03/06/16/23, read-write)")
              << " | " << f.address << " | " << f.words << " | " << type_name(f.type) << " | " << f.unit << " | "
              << f.description << " |\n";
  }
  return 0;
}

}  // namespace

void add_registers_command(CLI::App& app, Action& run) {
  auto* cmd = app.add_subcommand("registers", "print the Modbus register map (Markdown)");
  cmd->callback([&run] { run = [] { return run_registers(); }; });
}

}  // namespace dyncal::app
