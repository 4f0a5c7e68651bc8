#pragma once
/// The executor of `bvhbench suite --executor dask`: the jobs run on the workers of a Dask
/// distributed cluster, Dask being the engine. This side starts the bridge (run/dask_bridge.py,
/// in the project's Python with `dask` and `distributed`) and talks to it over a pipe, one JSON
/// object a line; the bridge is the Dask client.
///
/// What the bridge promises (its module docstring says how):
/// - each job runs on a worker as `bvhbench run-child ... -- bvhbench run ...`: its own child
///   process under the suite's limits, judged by the same code as a local job;
/// - the jobs of one comparison group (one mesh and one query set: JobTask::group) run on one
///   worker, one at a time, so ratios between methods are never taken across machines;
/// - a job whose worker is lost is run once more on another worker, then reported lost;
/// - the job's log and result come back here: the bridge writes logs/ID.log and, atomically,
///   runs/ID.json.child, so a result that came back survives a killed runner (--resume adopts
///   it); the runner then records it as for a local job.
///
/// Builds are not shared here: every job runs on its own (`bvhbench run`), with its own build
/// (submit_group is the default, one submit per job). The jobs of a comparison group (one mesh, one
/// query set) must stay on one worker, and the jobs of one structure span query sets: binding both
/// would put every job of a mesh on one worker, and the cluster would run a suite of one model on
/// one machine. Their results have no build.id and build.jobs 1 (docs/results.md, "Shared builds").
///
/// Meshes, query sets, oracle files and the bvhbench program are read by the workers at the
/// paths this machine gives: they must be on paths every worker shares (docs/dask.md).
#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <sys/types.h>

#include <nlohmann/json.hpp>

#include "harness/run/job_executor.hpp"

namespace bvhbench {

struct DaskOptions {
  std::string scheduler;     ///< a running scheduler's address; "": a local cluster on this machine
  int local_workers = 0;     ///< workers of the local cluster (0: one per core); ignored with `scheduler`
  std::string worker_exe;    ///< the bvhbench the workers run; "": this program's path
  std::string python;        ///< the interpreter of the bridge; "": dask_python()
  std::string bridge;        ///< the bridge script; "": dask_bridge_script()
};

/// The Python that runs the bridge: $BVHBENCH_PYTHON, else the project's venv (SOURCE/.venv)
/// when it exists, else `python3` on PATH.
std::string dask_python();
/// The bridge script: $BVHBENCH_DASK_BRIDGE, else SOURCE/harness/run/dask_bridge.py.
std::string dask_bridge_script();

/// The comparison group of a job: its mesh and its query set (not the method, not the query
/// type: every job over the same points on the same mesh is compared with the others).
std::string comparison_group(const JobPlan& plan);

class DaskJobExecutor : public JobExecutor {
 public:
  /// Starts the bridge and waits until it has a cluster. Throws InputError (exit 2) when it
  /// cannot: no Python, `dask`/`distributed` not installed, a scheduler that does not answer.
  explicit DaskJobExecutor(const DaskOptions& options);
  /// Tells the bridge that no more jobs come and waits for it to close its cluster.
  ~DaskJobExecutor() override;
  DaskJobExecutor(const DaskJobExecutor&) = delete;
  DaskJobExecutor& operator=(const DaskJobExecutor&) = delete;

  /// Unbounded: every job is handed to Dask as soon as its data is made; Dask and the bridge
  /// decide where and when it runs.
  std::size_t slots() const override;
  void submit(JobTask task) override;
  /// Waits for a job to end. On an interrupt (interrupt.hpp), asks the bridge to stop: jobs
  /// that had ended are returned as usual, the others with kept = false. Throws
  /// std::runtime_error if the bridge ends while jobs are pending.
  std::optional<JobFinished> collect() override;
  std::optional<JobFinished> collect_ready() override;
  std::size_t pending() const override { return tasks_.size(); }

 private:
  /// The next message of the bridge, waiting at most `wait_ms` (-1: until one comes).
  std::optional<nlohmann::json> read_message(int wait_ms);
  void send(const nlohmann::json& message);
  /// The job a message ends, as JobFinished; nullopt for a message that ends none.
  std::optional<JobFinished> finish(const nlohmann::json& message);
  void stop_on_interrupt();

  pid_t pid_ = -1;
  int to_bridge_ = -1, from_bridge_ = -1;
  std::string buffer_;
  bool eof_ = false, stop_sent_ = false;
  std::string worker_exe_;
  std::map<std::size_t, JobTask> tasks_;  // submitted, not yet collected, by JobTask::index
};

}  // namespace bvhbench
