// `bvhbench truth`: the exact oracle. Placeholder until issue 6 lands: the command exists so that
// the CLI is complete, and says plainly that it is not available yet.
#include <CLI/CLI.hpp>

#include "commands.hpp"
#include "errors.hpp"

namespace bvhbench {

void add_truth_command(CLI::App& app) {
  auto* cmd = app.add_subcommand("truth", "Compute oracle answers for a query set (not yet available)");
  cmd->allow_extras();
  cmd->callback([] { throw UnsupportedError("bvhbench truth is not implemented yet (issue 6)"); });
}

}  // namespace bvhbench
