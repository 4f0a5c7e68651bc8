#pragma once
/// The `bvhbench ebp` command group: `stats` (command_stats.cpp), `build` (command_build.cpp),
/// `info` (command_info.cpp) and `verify` (command_verify.cpp), attached by the method's
/// registration (ebp_method.cpp) through add_ebp_commands.
#include <map>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace bvhbench {

/// Adds `ebp` and its subcommands to `app`.
void add_ebp_commands(CLI::App& app);

void add_stats_command(CLI::App& ebp_cmd);
void add_build_command(CLI::App& ebp_cmd);
void add_info_command(CLI::App& ebp_cmd);
void add_verify_command(CLI::App& ebp_cmd);

/// The --param key=value arguments of `ebp stats` and `ebp build` as a map; throws InputError on
/// an argument without '=' or with an empty key, and on a key given twice.
std::map<std::string, std::string> parse_param_args(const std::vector<std::string>& kvs);

}  // namespace bvhbench
