#pragma once
// Subcommands that talk Modbus: drive (the simulated drive), calibrate, table, flash, registers.
#include <CLI/CLI.hpp>
#include <functional>
#include <string>

/// Adds the drive-related subcommands to `app`; each sets `run` to its action when chosen.
void add_drive_commands(CLI::App& app, std::function<int()>& run, const std::string& default_robots_dir);
