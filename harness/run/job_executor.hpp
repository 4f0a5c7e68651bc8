#pragma once
/// How the suite runner (suite_runner.hpp) has its jobs executed: the seam between the loop
/// (which jobs, in which order, --resume, the runs/ layout, summary.csv) and where a job runs.
/// LocalJobExecutor (local_job_executor.hpp) runs each in a child process on this machine;
/// DaskJobExecutor (dask_job_executor.hpp) on the workers of a Dask cluster.
///
/// What an executor must do:
/// - run each submitted job as `bvhbench run` with the task's arguments in its own child process
///   under the task's limits, or a submitted group's jobs in one child (`bvhbench run-group`) (child_process.hpp semantics: a crash, a hang, a blow-up is the
///   job's status, never the executor's or the runner's end);
/// - hand back, from collect(), each job's own result JSON, or the status row made from how its
///   child ended (job_status.hpp: status_row, group_status_rows) when it left none; the runner adds the job's
///   identity and writes it atomically to runs/ID.json, so executors write nothing there;
/// - while a job runs, it may keep its result at task.child_result_path (runs/ID.json.child):
///   a result found there by `--resume` is adopted, so a job that finished when the runner was
///   killed is not run again. A remote executor that cannot write there simply does not;
/// - on an interrupt (interrupt.hpp: interrupted()), stop what runs and report each unfinished
///   job with kept = false: the runner records it as not done, and --resume runs it again.
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/run/child_process.hpp"
#include "harness/run/run_job.hpp"
#include "harness/run/suite.hpp"

namespace bvhbench {

/// One job, ready to run: its query set and oracle exist (suite_data.hpp).
struct JobTask {
  std::size_t index = 0;             ///< its place among the jobs of this invocation
  /// The suite's round it runs in (1-based; suite_rounds.hpp), whose files are its paths below. A
  /// round is collected whole before the next is submitted, so `index` stays unique among the
  /// tasks pending.
  int round = 1;
  JobPlan plan;
  JobSpec spec;                      ///< what `bvhbench run` gets (method text, paths, repeat)
  ChildLimits limits;
  std::string child_result_path;     ///< runs/ID.json.child (a round: rounds/ID.round<k>.json.child): where a child may leave its result
  std::string log_path;              ///< logs/ID.log (a round: logs/ID.round<k>.log): the child's output
};

/// Jobs that share one structure (build_groups.hpp), ready to run: one child, one build.
struct GroupTask {
  std::string id;             ///< the build.id of their results
  std::vector<JobTask> jobs;  ///< in the order they run
  std::string plan_path;      ///< logs/GROUP.plan.json: where a child's plan is written (group_plan.hpp)
  std::string built_path;     ///< logs/GROUP.built.json: where the child says its build is done
};

/// A job that ended.
struct JobFinished {
  JobTask task;
  nlohmann::json result;   ///< the job's result or its status row (elapsed_seconds set)
  bool kept = true;        ///< false: an interrupt stopped it; no result to record
};

class JobExecutor {
 public:
  virtual ~JobExecutor() = default;
  /// How many jobs may be submitted and not yet collected; the runner prepares no more than
  /// that ahead of the ones running. At least 1.
  virtual std::size_t slots() const = 0;
  /// Starts the job, or queues it to start when a slot is free.
  virtual void submit(JobTask task) = 0;
  /// Starts the jobs of one structure, or queues them. An executor that shares the build runs
  /// them in one child, in order; when that child dies in one of them, the job that was running
  /// gets its status and the jobs after it `not_run`. The default runs each job on its own
  /// (submit), each with its own build.
  virtual void submit_group(GroupTask group) {
    for (JobTask& t : group.jobs) submit(std::move(t));
  }
  /// Whether submit_group() shares one build among a group's jobs (the suite's estimate prices
  /// builds by it).
  virtual bool shares_builds() const { return false; }
  /// Waits for a submitted job to end and returns it (in any order); nullopt when none is left.
  virtual std::optional<JobFinished> collect() = 0;
  /// A submitted job that has already ended, without waiting; nullopt when none has. An executor
  /// that runs jobs one at a time inside collect() has none (the default).
  virtual std::optional<JobFinished> collect_ready() { return std::nullopt; }
  /// Jobs submitted and not yet collected.
  virtual std::size_t pending() const = 0;
};

/// Reads the result file at `path` into `out`: false when it is missing, not JSON, or not an
/// object with a status (a job's half-written or foreign file is no result).
bool read_result_file(const std::string& path, nlohmann::json* out);

/// The arguments of `bvhbench run` for a job, after the program name and before `--out`
/// (an executor that runs the job elsewhere adds the result path it has there).
std::vector<std::string> run_arguments(const JobSpec& spec);

/// The `bvhbench run` command line of a task (args[0] = `exe`), writing its result to
/// task.child_result_path.
std::vector<std::string> run_command_line(const std::string& exe, const JobTask& task);

}  // namespace bvhbench
