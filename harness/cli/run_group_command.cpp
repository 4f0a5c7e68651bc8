// `bvhbench run-group --plan FILE`: the jobs of one structure in this process, one build for all
// (run/run_job.hpp: run_job_group). What the suite's local executor starts for each group of jobs
// (run/local_job_executor.hpp), in a child process under the suite's limits; each job's result is
// written as soon as it is final, so that the runner records it while the next job runs.
#include <fcntl.h>
#include <unistd.h>

#include <fstream>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "harness/cli/commands.hpp"
#include "harness/run/group_plan.hpp"
#include "harness/run/run_job.hpp"
#include "harness/util/printable.hpp"

namespace bvhbench {

namespace {

GroupPlan read_plan(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw InputError(printable(path) + ": cannot read the group plan");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(f);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(printable(path) + ": not JSON: " + e.what());
  }
  return group_plan_from_json(j, path);
}

/// This process's output from now on into `log` (each job's output in its own log).
void redirect_output(const std::string& log) {
  const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) return;  // the output stays where it was: nothing a job's result depends on
  fflush(stdout);
  fflush(stderr);
  dup2(fd, STDOUT_FILENO);
  dup2(fd, STDERR_FILENO);
  close(fd);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// `bvhbench run-group --plan FILE`
// ---------------------------------------------------------------------------------------------
void add_run_group_command(CLI::App& app) {
  auto plan_path = std::make_shared<std::string>();
  auto* cmd = app.add_subcommand(
      "run-group",
      "Run the jobs of one structure (one mesh, method and thread count) with one build, as a suite's child does: "
      "each job's result to its file as it ends (FILE: run/group_plan.hpp)");
  cmd->add_option("--plan", *plan_path, "The group's plan (JSON)")->required();
  cmd->callback([plan_path] {
    const GroupPlan plan = read_plan(*plan_path);
    std::vector<JobSpec> specs;
    for (const GroupPlanJob& g : plan.jobs) specs.push_back(g.spec);
    std::string current_log = plan.jobs.front().log;  // where the runner sent our output: the build's too
    GroupHooks hooks;
    hooks.built = [&](const nlohmann::json& build) {
      if (!plan.built.empty()) write_json_atomic(plan.built, build);
    };
    hooks.job_starts = [&](std::size_t k) {
      const std::string& log = plan.jobs[k].log;
      if (!log.empty() && log != current_log) redirect_output(log);
      current_log = log;
    };
    hooks.finished = [&](std::size_t k, const nlohmann::json& result) { write_json_atomic(plan.jobs[k].out, result); };
    run_job_group(specs, plan.build_id, hooks);
  });
}

}  // namespace bvhbench
