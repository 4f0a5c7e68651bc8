// `bvhbench run`: one job from the command line (run/run_job.hpp).
#include <iostream>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "harness/cli/commands.hpp"
#include "harness/core/registry.hpp"
#include "harness/run/run_job.hpp"

using json = nlohmann::json;

namespace bvhbench {

// ---------------------------------------------------------------------------------------------
// `bvhbench run`
// ---------------------------------------------------------------------------------------------
void add_run_command(CLI::App& app) {
  auto spec = std::make_shared<JobSpec>();
  auto out = std::make_shared<std::string>();
  auto query = std::make_shared<std::string>("inside");
  auto quiet = std::make_shared<bool>(false);
  auto method = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand("run", "Run one job: build one method on one mesh, replay one query set");
  cmd->add_option("--mesh", spec->mesh_path, "Mesh (PLY, OBJ, STL or OFF)")->required();
  cmd->add_option("--method", *method, "NAME or NAME:key=value,...")->required();
  cmd->add_option("--queries", spec->queries_path,
                  "Query set: .npy from bvhbench queries (with its .json sidecar), or points made "
                  "elsewhere: .npy (float64/float32, N x 3) or .xyz/.csv text, one point a line")
      ->required();
  cmd->add_option("--query", *query, "inside | distance")->check(CLI::IsMember({"inside", "distance"}));
  cmd->add_option("--repeat", spec->repeat, "Timed passes after the warm-up")->check(CLI::Range(1, 1000));
  cmd->add_option("--threads", spec->threads, "Query threads T (random points split, haptic paths as T probes); also the build's thread budget")->check(CLI::Range(1, 1024));
  cmd->add_option("--truth", spec->truth_path, "Oracle .npz (bvhbench truth) -> accuracy block");
  cmd->add_option("--answers", spec->answers_path, "Write the per-query answers to this .npz");
  cmd->add_option("--out", *out, "Result JSON (default: stdout)");
  cmd->add_option("--deadline-ns", spec->deadline_ns, "Per-query deadline (haptic loop: 1e6 ns)");
  cmd->add_flag("--quiet", *quiet, "No progress on stderr");
  cmd->callback([=] {
    // Parsed once, here; a spec that cannot be resolved is the job's rejected_input result.
    spec->method = Registry::global().describe(*method);
    spec->query_type = parse_query_type(*query);
    spec->progress = !*quiet;
    json r = run_job(*spec);
    if (out->empty()) std::cout << dump_result(r) << std::endl;
    else write_json_atomic(*out, r);
    std::string st = r["status"];
    if (st != status::ok) {
      std::cerr << "bvhbench run: " << st << ": " << r["message"].get<std::string>() << "\n";
      throw ExitCode{st == status::rejected_input ? 2 : 1};
    }
  });
}

}  // namespace bvhbench
