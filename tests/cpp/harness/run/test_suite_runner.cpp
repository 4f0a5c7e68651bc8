// The suite loop (run/suite_runner.hpp) through its executor seam: an executor that runs
// nothing shows what the runner itself owes every executor's results (the runs/ layout, the
// job's identity, summary.csv, --resume).
#include <gtest/gtest.h>

#include <deque>
#include <string>

#include "harness/run/suite_runner.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {

/// Answers every job at once with a result of its own making, and remembers what it was given.
class CannedExecutor : public JobExecutor {
 public:
  std::size_t slots() const override { return 2; }
  void submit(JobTask task) override {
    submitted.push_back(task.plan.id);
    queue_.push_back(std::move(task));
  }
  std::optional<JobFinished> collect() override {
    if (queue_.empty()) return std::nullopt;
    JobFinished f{queue_.front(), nlohmann::json::object(), true};
    queue_.pop_front();
    f.result = make_result(f.task.spec, status::ok, "");
    f.result["elapsed_seconds"] = 0.5;
    args.push_back(run_command_line("bvhbench", f.task));
    return f;
  }
  std::size_t pending() const override { return queue_.size(); }

  std::vector<std::string> submitted;
  std::vector<std::vector<std::string>> args;

 private:
  std::deque<JobTask> queue_;
};

}  // namespace

TEST(SuiteRunner, ResultsOfAnExecutorAreWrittenWithTheirJobAndResumed) {
  TmpDir d;
  write_file_bytes(d.file("p.xyz"), "0 0 0\n1 1 1\n");
  write_file_bytes(d.file("s.yml"),
                   "name: canned\ntruth: false\nrepeat: 3\nmatrices:\n  - meshes: [m.ply]\n    queries: [{file: p.xyz}]\n"
                   "    query: [inside, distance]\n    methods: [\"brute_force:winding_threshold=0.25\", fault]\n");
  const SuiteConfig cfg = load_suite(d.file("s.yml"));
  ASSERT_EQ(cfg.jobs.size(), 4u);
  SuiteRunOptions options;
  options.out = d.file("out");

  CannedExecutor first;
  const SuiteRunSummary s = run_suite(cfg, cfg.jobs, options, first);
  EXPECT_EQ(s.recorded, 4u);
  EXPECT_EQ(s.resumed, 0u);
  EXPECT_EQ(s.not_ok, 0u);
  EXPECT_FALSE(s.interrupted);
  ASSERT_EQ(first.submitted.size(), 4u);
  EXPECT_EQ(first.submitted[0], cfg.jobs[0].id);
  // The child's command line: the method's text as the suite gave it, the limits' repeat.
  const std::vector<std::string> want = {"bvhbench", "--quiet", "run", "--mesh", cfg.jobs[0].mesh.path, "--method",
                                         "brute_force:winding_threshold=0.25", "--queries", d.file("p.xyz"), "--query",
                                         "inside", "--repeat", "3", "--out",
                                         d.file("out/runs/" + cfg.jobs[0].id + ".json.child")};
  EXPECT_EQ(first.args[0], want);
  for (const JobPlan& j : cfg.jobs) {
    SCOPED_TRACE(j.id);
    nlohmann::json r;
    ASSERT_TRUE(read_result_file(d.file("out/runs/" + j.id + ".json"), &r));
    EXPECT_EQ(r["job"]["id"], j.id);
    EXPECT_EQ(r["job"]["suite"], "canned");
    EXPECT_EQ(r["job"]["mesh"]["name"], "m");
    EXPECT_EQ(r["job"]["method_spec"], j.method.text);
    EXPECT_TRUE(leftover_temporaries(d.file("out/runs/" + j.id + ".json")).empty());
  }
  EXPECT_EQ(read_file_bytes(d.file("out/suite.yml")), read_file_bytes(d.file("s.yml")));
  EXPECT_TRUE(std::filesystem::exists(d.file("out/summary.csv")));

  // --resume: nothing left to run; a result a child left behind (.child) is adopted.
  std::filesystem::rename(d.file("out/runs/" + cfg.jobs[3].id + ".json"), d.file("out/runs/" + cfg.jobs[3].id + ".json.child"));
  options.resume = true;
  CannedExecutor again;
  const SuiteRunSummary r = run_suite(cfg, cfg.jobs, options, again);
  EXPECT_TRUE(again.submitted.empty());
  EXPECT_EQ(r.recorded, 4u);
  EXPECT_EQ(r.resumed, 4u);
  EXPECT_TRUE(std::filesystem::exists(d.file("out/runs/" + cfg.jobs[3].id + ".json")));
  EXPECT_FALSE(std::filesystem::exists(d.file("out/runs/" + cfg.jobs[3].id + ".json.child")));
}

TEST(SuiteRunner, AMissingPointsFileIsTheJobsRowWithoutRunningIt) {
  TmpDir d;
  write_file_bytes(d.file("s.yml"), "truth: false\nmatrices:\n  - meshes: [m.ply]\n    queries: [{file: gone.xyz}]\n"
                                    "    query: [inside]\n    methods: [brute_force]\n");
  const SuiteConfig cfg = load_suite(d.file("s.yml"));
  SuiteRunOptions options;
  options.out = d.file("out");
  CannedExecutor executor;
  const SuiteRunSummary s = run_suite(cfg, cfg.jobs, options, executor);
  EXPECT_TRUE(executor.submitted.empty());
  EXPECT_EQ(s.not_ok, 1u);
  nlohmann::json r;
  ASSERT_TRUE(read_result_file(d.file("out/runs/" + cfg.jobs[0].id + ".json"), &r));
  EXPECT_EQ(r["status"], "rejected_input");
  EXPECT_EQ(r["message"], "query set refused: " + d.file("gone.xyz") + ": points file not found");
}
