#include "harness/run/job_status.hpp"

#include <signal.h>

#include <cstring>

#include "harness/util/printable.hpp"
#include "harness/util/progress.hpp"

namespace bvhbench {

using json = nlohmann::json;

namespace {

/// What a result says of its query set when the job left none: the plan. A points file has no
/// n or seed until it is read.
void set_planned_queries(json& r, const QueryPlan& q, bool with_seed) {
  r["job"]["queries"]["kind"] = q.kind;
  if (!q.file.empty()) {
    r["job"]["queries"]["path"] = printable(q.file);
    return;
  }
  r["job"]["queries"]["n"] = q.n;
  if (with_seed) r["job"]["queries"]["seed"] = q.seed;
}

}  // namespace

ChildStatus child_status(const ChildOutcome& o, double timeout_s) {
  ChildStatus s;
  bool bad_alloc = o.stderr_tail.find("bad_alloc") != std::string::npos ||
                   o.stderr_tail.find("out of memory") != std::string::npos ||
                   o.stderr_tail.find("Cannot allocate memory") != std::string::npos;
  if (o.timed_out) {
    s.code = status::timeout;
    s.message = "killed after the time limit of " + format_seconds(timeout_s);
  } else if (o.signal == SIGKILL || bad_alloc) {
    s.code = status::oom;
    s.message = o.signal == SIGKILL ? "killed (SIGKILL: out of memory?)" : "out of memory";
  } else if (o.signal) {
    s.code = status::crash;
    s.message = std::string("killed by signal ") + std::to_string(o.signal) + " (" + strsignal(o.signal) + ")";
  } else {
    s.code = o.exit_code == 2 ? status::rejected_input : status::error;
    s.message = "exit code " + std::to_string(o.exit_code) + " without a result";
  }
  if (!o.stderr_tail.empty()) {
    std::string t = o.stderr_tail;
    if (t.size() > 500) t = "..." + t.substr(t.size() - 500);
    s.message += "; stderr: " + t;
  }
  return s;
}

json job_failure_row(const JobSpec& spec, const JobPlan& plan, const std::string& code, const std::string& message) {
  json r = make_result(spec, code, message);
  r["job"]["id"] = plan.id;
  r["job"]["mesh"]["name"] = plan.mesh.name;
  set_planned_queries(r, plan.queries, true);
  return r;
}

json status_row(const JobSpec& spec, const JobPlan& plan, const ChildOutcome& o, double timeout_s) {
  const ChildStatus s = child_status(o, timeout_s);
  json r = job_failure_row(spec, plan, s.code, s.message);
  r["elapsed_seconds"] = o.seconds;
  return r;
}

json query_set_failure_row(const JobSpec& spec, const JobPlan& plan, const std::string& error) {
  json r = make_result(spec, error.find("exit code") == std::string::npos ? status::rejected_input : status::error,
                       (plan.queries.file.empty() ? "query set could not be made: " : "query set refused: ") + error);
  r["job"]["id"] = plan.id;
  r["job"]["mesh"]["name"] = plan.mesh.name;
  set_planned_queries(r, plan.queries, false);
  return r;
}

}  // namespace bvhbench
