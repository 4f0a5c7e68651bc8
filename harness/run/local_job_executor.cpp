#include "harness/run/local_job_executor.hpp"

#include <cstdio>

#include "harness/run/interrupt.hpp"
#include "harness/run/job_status.hpp"

namespace bvhbench {

std::optional<JobFinished> LocalJobExecutor::collect() {
  if (queue_.empty()) return std::nullopt;
  JobFinished f{std::move(queue_.front()), nlohmann::json(), true};
  queue_.pop_front();
  const JobTask& t = f.task;
  const ChildOutcome oc = run_child(run_command_line(exe_, t), t.limits, t.log_path);
  const bool wrote = read_result_file(t.child_result_path, &f.result);
  // Interrupted: keep a job that finished on its own, drop one the interrupt killed.
  if (interrupted() && !(wrote && oc.exited)) {
    std::remove(t.child_result_path.c_str());
    f.kept = false;
    return f;
  }
  if (!wrote) f.result = status_row(t.spec, t.plan, oc, t.limits.timeout_s);
  f.result["elapsed_seconds"] = oc.seconds;
  return f;
}

}  // namespace bvhbench
