#pragma once
/// The result row of a suite job that left no result of its own: its child died (a crash, a
/// timeout, out of memory, an exit without a result), or its query set could not be made. The
/// row has the job block of the plan (run_job.hpp: job_block), so it pairs and groups with the
/// job's own rows in compare and summary.csv.
#include <string>

#include <nlohmann/json.hpp>

#include "harness/run/child_process.hpp"
#include "harness/run/run_job.hpp"
#include "harness/run/suite.hpp"

namespace bvhbench {

/// A status code of the contract (run_job.hpp: status) and its message.
struct ChildStatus {
  std::string code;
  std::string message;
};

/// What a child's end means for its job: timeout (it exceeded `timeout_s`), oom (SIGKILL, or
/// its output mentions bad_alloc / out of memory / "Cannot allocate memory"), crash (another
/// signal), rejected_input (exit code 2) or error (any other exit). The message says how it
/// ended and ends with the last 500 bytes of its output.
ChildStatus child_status(const ChildOutcome& outcome, double timeout_s);

/// The row of a job that left no result of its own, with status `code` and `message`: the plan's
/// id, mesh name and planned query set (n and seed, or the points file's path).
nlohmann::json job_failure_row(const JobSpec& spec, const JobPlan& plan, const std::string& code,
                               const std::string& message);

/// The row of a job whose child left no result file: child_status() with the plan's id, mesh
/// name and planned query set, and the child's elapsed_seconds.
nlohmann::json status_row(const JobSpec& spec, const JobPlan& plan, const ChildOutcome& outcome,
                          double timeout_s);

/// The row of a job whose query set could not be made (a generated one: `error` is the
/// generator's output) or was refused (a points file). rejected_input, or error when the
/// generator only left "exit code ..." behind.
nlohmann::json query_set_failure_row(const JobSpec& spec, const JobPlan& plan, const std::string& error);

}  // namespace bvhbench
