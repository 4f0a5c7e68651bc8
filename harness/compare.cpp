// `bvhbench compare`: placeholder until issue 9 lands.
#include <CLI/CLI.hpp>

#include "commands.hpp"
#include "errors.hpp"

namespace bvhbench {

void add_compare_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("compare", "Compare a baseline with a new result set (not yet available)");
  cmd->allow_extras();
  cmd->callback([] { throw UnsupportedError("bvhbench compare is not implemented yet (issue 9)"); });
}

}  // namespace bvhbench
