// `bvhbench compare BASE NEW`: the command line over run/compare.hpp (docs/compare.md).
#include <iostream>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "harness/cli/commands.hpp"
#include "harness/run/compare.hpp"
#include "harness/run/compare_markdown.hpp"

using json = nlohmann::json;

namespace bvhbench {

// ---------------------------------------------------------------------------------------------
// `bvhbench compare`
// ---------------------------------------------------------------------------------------------
void add_compare_command(CLI::App& app) {
  struct Opts {
    std::string base, fresh, format = "md", timing = "gate";
    CompareOptions c;
  };
  auto o = std::make_shared<Opts>();
  auto* cmd = app.add_subcommand("compare", "Compare a baseline with a new result set; exit 1 on a regression");
  cmd->add_option("base", o->base, "Baseline: result folder (with runs/*.json) or one result file")->required();
  cmd->add_option("new", o->fresh, "New results: result folder or one result file")->required();
  cmd->add_option("--threshold", o->c.threshold, "Relative throughput change that matters (default 0.10)")
      ->check(CLI::Range(0.0, 100.0));
  cmd->add_option("--alpha", o->c.alpha, "Significance level of the Mann-Whitney U test (default 0.01)")
      ->check(CLI::Range(1e-12, 1.0));
  cmd->add_option("--format", o->format, "md (Markdown table) or json")
      ->check(CLI::IsMember({"md", "json"}))
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
  cmd->add_option("--timing", o->timing, "gate (default: slower throughput fails) or report (shown, never fails)")
      ->check(CLI::IsMember({"gate", "report"}))
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);  // scripts append to CI's defaults
  cmd->add_flag("--ignore-missing", o->c.ignore_missing, "Jobs of BASE absent from NEW do not fail (partial runs)");
  cmd->add_option("--rtol", o->c.rtol, "Relative tolerance for floating accuracy summaries (default 1e-12)")
      ->check(CLI::Range(0.0, 1.0));
  cmd->callback([o] {
    o->c.timing_gates = o->timing == "gate";
    ResultSet base = load_result_set(o->base);
    ResultSet fresh = load_result_set(o->fresh);
    json rep = compare_result_sets(base, fresh, o->c);
    if (o->format == "json") std::cout << rep.dump(2) << "\n";
    else std::cout << compare_markdown(rep);
    std::cout.flush();
    if (rep["exit_code"].get<int>() != 0) throw ExitCode{rep["exit_code"].get<int>()};
  });
}

}  // namespace bvhbench
