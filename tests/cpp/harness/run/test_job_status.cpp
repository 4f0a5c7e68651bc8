// The status row of a suite job whose child left no result (run/job_status.hpp): how a child's
// end maps to a status of the contract, and the job block it carries.
#include <gtest/gtest.h>
#include <signal.h>

#include <string>

#include "harness/core/registry.hpp"
#include "harness/run/job_status.hpp"

using namespace bvhbench;

namespace {
ChildOutcome exited(int code, std::string tail = "") {
  ChildOutcome o;
  o.exited = true;
  o.exit_code = code;
  o.stderr_tail = std::move(tail);
  return o;
}
ChildOutcome killed(int signal, std::string tail = "") {
  ChildOutcome o;
  o.signal = signal;
  o.stderr_tail = std::move(tail);
  return o;
}
}  // namespace

TEST(JobStatus, HowAChildEndedIsItsStatus) {
  ChildOutcome late = killed(SIGKILL);
  late.timed_out = true;
  struct Case {
    ChildOutcome o;
    std::string code, message;
  };
  for (const Case& c : {
           Case{late, "timeout", "killed after the time limit of 1m30s"},
           Case{killed(SIGKILL), "oom", "killed (SIGKILL: out of memory?)"},
           Case{exited(1, "what(): std::bad_alloc"), "oom", "out of memory; stderr: what(): std::bad_alloc"},
           Case{killed(SIGABRT, "terminate: Cannot allocate memory"), "oom",
                "out of memory; stderr: terminate: Cannot allocate memory"},
           Case{killed(SIGSEGV), "crash", "killed by signal 11 (Segmentation fault)"},
           Case{exited(2, "bvhbench: m.ply: bad header"), "rejected_input",
                "exit code 2 without a result; stderr: bvhbench: m.ply: bad header"},
           Case{exited(0), "error", "exit code 0 without a result"},
           Case{exited(1), "error", "exit code 1 without a result"},
       }) {
    SCOPED_TRACE(c.message);
    const ChildStatus s = child_status(c.o, 90);
    EXPECT_EQ(s.code, c.code);
    EXPECT_EQ(s.message, c.message);
  }
}

TEST(JobStatus, TheMessageKeepsTheLast500BytesOfTheOutput) {
  const ChildStatus s = child_status(exited(1, std::string(400, 'a') + std::string(400, 'b')), 1);
  EXPECT_EQ(s.message, "exit code 1 without a result; stderr: ..." + std::string(100, 'a') + std::string(400, 'b'));
}

TEST(JobStatus, TheRowCarriesThePlannedJob) {
  JobPlan plan;
  plan.id = "m__random-n10__inside__brute_force";
  plan.mesh = {"m", "/x/m.ply"};
  plan.queries.n = 10;
  plan.queries.seed = 7;
  plan.method = Registry::global().resolve("brute_force:winding_threshold=0.25");
  JobSpec spec;
  spec.mesh_path = plan.mesh.path;
  spec.method = plan.method;
  spec.queries_path = "/d/q.npy";
  ChildOutcome o = killed(SIGSEGV);
  o.seconds = 1.5;
  const nlohmann::json r = status_row(spec, plan, o, 60);
  EXPECT_EQ(r["status"], "crash");
  EXPECT_EQ(r["elapsed_seconds"], 1.5);
  EXPECT_EQ(r["job"]["id"], plan.id);
  EXPECT_EQ(r["job"]["mesh"]["name"], "m");
  EXPECT_EQ(r["job"]["method"], "brute_force");
  EXPECT_EQ(r["job"]["method_spec"], "brute_force:winding_threshold=0.25");
  EXPECT_EQ(r["job"]["params_key"], "winding_threshold=0.25");
  EXPECT_EQ(r["job"]["queries"]["kind"], "random");
  EXPECT_EQ(r["job"]["queries"]["n"], 10);
  EXPECT_EQ(r["job"]["queries"]["seed"], 7);

  // A query set that could not be made: no seed (none was used); a points file: its path.
  const nlohmann::json made = query_set_failure_row(spec, plan, "m.ply: bad header");
  EXPECT_EQ(made["status"], "rejected_input");
  EXPECT_EQ(made["message"], "query set could not be made: m.ply: bad header");
  EXPECT_FALSE(made["job"]["queries"].contains("seed"));
  EXPECT_EQ(query_set_failure_row(spec, plan, "exit code 1 without a result")["status"], "error");
  plan.queries.kind = "file";
  plan.queries.file = "/p/points.xyz";
  plan.queries.name = "points";
  const nlohmann::json refused = query_set_failure_row(spec, plan, "/p/points.xyz: points file not found");
  EXPECT_EQ(refused["message"], "query set refused: /p/points.xyz: points file not found");
  EXPECT_EQ(refused["job"]["queries"]["path"], "/p/points.xyz");
  EXPECT_FALSE(refused["job"]["queries"].contains("n"));
}
