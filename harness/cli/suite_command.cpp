// `bvhbench suite SUITE.yml --out results/NAME`: the command's options. The suite file is read
// by run/suite.hpp, run by run/suite_runner.hpp, each job in its own child process: on this
// machine (run/local_job_executor.hpp) or on the workers of a Dask cluster
// (run/dask_job_executor.hpp).
#include <iostream>
#include <memory>
#include <regex>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "harness/cli/commands.hpp"
#include "harness/run/child_process.hpp"
#include "harness/run/dask_job_executor.hpp"
#include "harness/run/local_job_executor.hpp"
#include "harness/run/suite.hpp"
#include "harness/run/suite_runner.hpp"
#include "harness/util/errors.hpp"

namespace bvhbench {

// ---------------------------------------------------------------------------------------------
// `bvhbench suite SUITE.yml --out results/NAME [--resume] [--filter REGEX] [--rounds N]
//                  [--executor local|dask [--scheduler ADDRESS]]`
// ---------------------------------------------------------------------------------------------
namespace {

struct SuiteOpts {
  std::string file, out, filter, data_dir, executor = "local", scheduler, worker_exe;
  int dask_workers = 0;
  bool resume = false, list = false, json = false, no_truth = false, estimate = false;
  double timeout_s = -1, memory_limit_mb = -1;
  int repeat = -1;
  int rounds = -1;
};

void add_suite_options(CLI::App* cmd, SuiteOpts& o) {
  cmd->add_option("suite", o.file,
                  "Suite file (suites/*.yml): meshes x query sets (generated, or points files given as "
                  "{file: PATH}) x queries x methods; format in suites/README.md")
      ->required();
  cmd->add_option("--out", o.out, "Result folder (results/NAME; not needed with --list)");
  cmd->add_flag("--resume", o.resume, "Skip jobs whose result is already written");
  cmd->add_option("--filter", o.filter, "Run only jobs whose id matches this regex");
  cmd->add_flag("--list", o.list, "Print the expanded job ids and exit, running nothing");
  cmd->add_flag("--json", o.json,
                "With --list: every job as JSON (id, mesh, query set, query, method and its canonical key, threads, "
                "repeat): what tools read instead of the suite file. With --estimate: each job's expected seconds "
                "and the part of them that builds its structure");
  cmd->add_flag("--estimate", o.estimate,
                "Print how long the suite is expected to take here (with --resume: what is left), and exit");
  cmd->add_option("--timeout", o.timeout_s, "Per-job time limit in seconds (overrides the suite)");
  cmd->add_option("--memory-limit", o.memory_limit_mb, "Per-job address-space limit in MiB (overrides the suite)");
  cmd->add_option("--repeat", o.repeat, "Timed passes per job (overrides the suite)");
  cmd->add_option("--rounds", o.rounds,
                  "Times every job is run, round after round over the whole suite, keeping each job's round of the "
                  "highest median throughput (overrides the suite's rounds:; suites/README.md)")
      ->check(CLI::Range(1, kMaxSuiteRounds));
  cmd->add_flag("--no-truth", o.no_truth, "Do not compute or attach oracle answers");
  cmd->add_option("--data", o.data_dir, "Cache for query sets and oracle files (default: OUT/data)");
  cmd->add_option("--executor", o.executor,
                  "Where the jobs run: local (here, one at a time) or dask (on a Dask cluster; docs/dask.md)")
      ->check(CLI::IsMember({"local", "dask"}));
  cmd->add_option("--scheduler", o.scheduler,
                  "With --executor dask: a running Dask scheduler (tcp://HOST:PORT); default: a local cluster here");
  cmd->add_option("--dask-workers", o.dask_workers,
                  "With --executor dask and no --scheduler: workers of the local cluster (default: one per core)")
      ->check(CLI::Range(1, 4096));
  cmd->add_option("--worker-exe", o.worker_exe,
                  "With --executor dask: the bvhbench the workers run (default: this program's path)");
}

/// The suite file with the command line's overrides.
SuiteConfig load_with_overrides(const SuiteOpts& o) {
  if (o.executor != "dask" && (!o.scheduler.empty() || o.dask_workers > 0 || !o.worker_exe.empty()))
    throw InputError("--scheduler, --dask-workers and --worker-exe need --executor dask");
  if (!o.scheduler.empty() && o.dask_workers > 0)
    throw InputError("--dask-workers sizes the local cluster; a cluster at --scheduler has its own workers");
  SuiteConfig cfg = load_suite(o.file);
  if (o.timeout_s > 0) cfg.timeout_s = o.timeout_s;
  if (o.memory_limit_mb >= 0) cfg.memory_limit_mb = o.memory_limit_mb;
  if (o.repeat > 0) cfg.repeat = o.repeat;
  if (o.rounds > 0) cfg.rounds = o.rounds;
  if (o.no_truth) cfg.truth = false;
  return cfg;
}

/// The suite's jobs whose id matches --filter.
std::vector<JobPlan> filtered_jobs(const SuiteConfig& cfg, const std::string& filter) {
  std::regex re;
  try {
    re = std::regex(filter.empty() ? ".*" : filter);
  } catch (const std::regex_error& e) {
    throw InputError("--filter '" + filter + "': bad regex: " + e.what());
  }
  std::vector<JobPlan> jobs;
  for (auto& j : cfg.jobs)
    if (std::regex_search(j.id, re)) jobs.push_back(j);
  return jobs;
}

void run_suite_command(const SuiteOpts& o) {
  const SuiteConfig cfg = load_with_overrides(o);
  const std::vector<JobPlan> jobs = filtered_jobs(cfg, o.filter);
  if (o.list) {
    if (o.json) {
      std::cout << suite_jobs_json(cfg, jobs).dump(1) << "\n";
      return;
    }
    for (auto& j : jobs) std::cout << j.id << "\n";
    // Beside the ids, which tools read from stdout one per line.
    if (cfg.rounds > 1) std::cerr << "suite " << cfg.name << ": each job runs in " << cfg.rounds << " rounds\n";
    return;
  }
  if (o.json && !o.estimate) throw InputError("--json goes with --list or --estimate");
  if (o.out.empty()) throw InputError("--out is required (a result folder, results/NAME)");
  SuiteRunOptions run;
  run.out = o.out;
  run.data_dir = o.data_dir;
  run.resume = o.resume;
  if (o.estimate) {
    // The local executor shares builds, Dask's does not (dask_job_executor.hpp says why).
    const SuitePrice price = estimate_suite(cfg, jobs, run, o.executor == "local");
    std::cerr << "suite " << cfg.name << ": " << price.describe() << "\n";
    if (o.json) std::cout << price_json(price, jobs).dump(1) << "\n";
    return;
  }
  std::unique_ptr<JobExecutor> executor;
  if (o.executor == "dask")
    executor = std::make_unique<DaskJobExecutor>(DaskOptions{o.scheduler, o.dask_workers, o.worker_exe, "", ""});
  else
    executor = std::make_unique<LocalJobExecutor>(self_exe());
  const bool interrupted = run_suite(cfg, jobs, run, *executor).interrupted;
  executor.reset();  // a cluster is closed before the command ends
  if (interrupted) throw ExitCode{130};
}

}  // namespace

void add_suite_command(CLI::App& app) {
  auto o = std::make_shared<SuiteOpts>();
  auto* cmd = app.add_subcommand("suite", "Run a YAML matrix of jobs, each in its own child process");
  add_suite_options(cmd, *o);
  cmd->callback([o] { run_suite_command(*o); });
}

}  // namespace bvhbench
