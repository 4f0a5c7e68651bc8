// The `bvhbench ebp` group (commands.hpp): its subcommands and what two of them share.
#include "methods/ebp_octree/commands.hpp"

#include "harness/util/key_value.hpp"

namespace bvhbench {

void add_ebp_commands(CLI::App& app) {
  auto* ebp_cmd = app.add_subcommand("ebp", "EBP-Octree tools (stats; build/info/verify for the on-disk store)");
  ebp_cmd->require_subcommand(1);
  add_stats_command(*ebp_cmd);
  add_build_command(*ebp_cmd);
  add_info_command(*ebp_cmd);
  add_verify_command(*ebp_cmd);
}

std::map<std::string, std::string> parse_param_args(const std::vector<std::string>& kvs) {
  std::map<std::string, std::string> given;
  for (const std::string& kv : kvs) add_key_value(kv, "--param", given);
  return given;
}

}  // namespace bvhbench
