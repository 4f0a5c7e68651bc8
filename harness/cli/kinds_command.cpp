// `bvhbench kinds`: the registered query kinds (query_set.hpp), what each makes, whether it is a
// path replayed in order, and its generator's parameters with their defaults and ranges. The
// reports and tests read the kinds from here (`--json`) rather than naming them.
#include <iostream>
#include <memory>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "harness/cli/commands.hpp"
#include "harness/cli/param_listing.hpp"
#include "harness/core/query_set.hpp"

namespace bvhbench {

void add_kinds_command(CLI::App& app) {
  auto as_json = std::make_shared<bool>(false);
  auto* cmd = app.add_subcommand("kinds", "List the query kinds, their parameters and defaults");
  cmd->add_flag("--json", *as_json, "Machine-readable output");
  cmd->callback([=] {
    nlohmann::json out = nlohmann::json::array();
    for (const QueryKind& k : query_kinds()) {
      const std::string owner = "query kind '" + k.name + "'";
      if (*as_json) {
        out.push_back({{"name", k.name},
                       {"description", k.description},
                       {"ordered", k.ordered},
                       {"params", params_json(owner, k.params)}});
        continue;
      }
      std::cout << k.name << (k.ordered ? " [a path, replayed in order]" : "") << "\n  " << k.description << "\n";
      print_params(std::cout, owner, k.params);
      std::cout << "\n";
    }
    if (*as_json) std::cout << out.dump(2) << "\n";
  });
}

}  // namespace bvhbench
