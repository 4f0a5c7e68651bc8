#pragma once
/// The `bvhbench` subcommands. Each add_*_command() adds one subcommand with its options and
/// callback to the CLI app; main.cpp calls them all, then the commands methods register.
/// Callbacks report failure by throwing: InputError (exit 2) or ExitCode (any code), both in
/// harness/util/errors.hpp.
#include "harness/util/errors.hpp"

namespace CLI { class App; }

namespace bvhbench {

void add_methods_command(CLI::App& app);    // methods_command.cpp
void add_kinds_command(CLI::App& app);      // kinds_command.cpp
void add_queries_command(CLI::App& app);    // queries_command.cpp
void add_run_command(CLI::App& app);        // run_command.cpp
void add_suite_command(CLI::App& app);      // suite_command.cpp
void add_run_child_command(CLI::App& app);  // run_child_command.cpp
void add_run_group_command(CLI::App& app);  // run_group_command.cpp
void add_truth_command(CLI::App& app);      // truth_command.cpp
void add_compare_command(CLI::App& app);    // compare_command.cpp
void add_mesh_info_command(CLI::App& app);  // mesh_info_command.cpp

}  // namespace bvhbench
