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

namespace {

/// Answers round k of every job at the rate rates[k - 1] queries/s, and remembers what it was
/// given, in order.
class RoundsExecutor : public JobExecutor {
 public:
  explicit RoundsExecutor(std::vector<double> rates) : rates_(std::move(rates)) {}
  std::size_t slots() const override { return 1; }
  void submit(JobTask task) override {
    submitted.push_back({task.round, task.plan.id});
    child_paths.push_back(task.child_result_path);
    queue_.push_back(std::move(task));
  }
  std::optional<JobFinished> collect() override {
    if (queue_.empty()) return std::nullopt;
    JobFinished f{queue_.front(), nlohmann::json::object(), true};
    queue_.pop_front();
    const double qps = rates_.at(std::size_t(f.task.round - 1));
    f.result = make_result(f.task.spec, status::ok, "");
    f.result["queries"] = {{"throughput_qps", {{"median", qps}, {"min", qps}, {"max", qps}, {"samples", {qps}}}}};
    f.result["elapsed_seconds"] = 0.1;
    return f;
  }
  std::size_t pending() const override { return queue_.size(); }

  std::vector<std::pair<int, std::string>> submitted;  // (round, job id)
  std::vector<std::string> child_paths;

 private:
  std::vector<double> rates_;
  std::deque<JobTask> queue_;
};

}  // namespace

// rounds: 3 runs every job three times, round-major, each round's result kept on its own, each
// job's result the best round's with the record of all three; --resume runs only what is missing.
TEST(SuiteRunner, ASuiteInRoundsRunsEveryJobOncePerRoundAndKeepsTheBest) {
  TmpDir d;
  write_file_bytes(d.file("p.xyz"), "0 0 0\n1 1 1\n");
  write_file_bytes(d.file("s.yml"), "name: rounds\ntruth: false\nrepeat: 1\nrounds: 3\nmatrices:\n"
                                    "  - meshes: [a.ply, b.ply]\n    queries: [{file: p.xyz}]\n"
                                    "    query: [inside]\n    methods: [brute_force, fault]\n");
  const SuiteConfig cfg = load_suite(d.file("s.yml"));
  ASSERT_EQ(cfg.jobs.size(), 4u);
  SuiteRunOptions options;
  options.out = d.file("out");
  RoundsExecutor first({100, 300, 200});
  const SuiteRunSummary s = run_suite(cfg, cfg.jobs, options, first);
  EXPECT_EQ(s.recorded, 4u);
  ASSERT_EQ(first.submitted.size(), 12u);
  for (std::size_t k = 0; k < 12; ++k) EXPECT_EQ(first.submitted[k].first, int(k / 4) + 1) << k;  // round-major
  EXPECT_EQ(first.child_paths[4], d.file("out/rounds/" + first.submitted[4].second + ".round2.json.child"));
  for (const JobPlan& j : cfg.jobs) {
    SCOPED_TRACE(j.id);
    nlohmann::json r;
    ASSERT_TRUE(read_result_file(d.file("out/runs/" + j.id + ".json"), &r));
    EXPECT_EQ(r["job"]["id"], j.id);
    EXPECT_EQ(r["queries"]["throughput_qps"]["median"], 300);
    EXPECT_EQ(r["rounds"]["count"], 3);
    EXPECT_EQ(r["rounds"]["kept"], 2);
    ASSERT_EQ(r["rounds"]["by_round"].size(), 3u);
    EXPECT_EQ(r["rounds"]["by_round"][2]["throughput_qps"]["median"], 200);
    for (int k = 1; k <= 3; ++k) {
      nlohmann::json round;
      ASSERT_TRUE(read_result_file(d.file("out/rounds/" + j.id + ".round" + std::to_string(k) + ".json"), &round));
      EXPECT_EQ(round["job"]["id"], j.id);  // stamped like any result
      EXPECT_FALSE(round.contains("rounds"));
    }
  }
  EXPECT_NE(read_file_bytes(d.file("out/summary.csv")).find(",300,300,300,2,3,"), std::string::npos)
      << read_file_bytes(d.file("out/summary.csv"));

  // A runner killed after round 2: round 3 of one job and its result gone. --resume runs that
  // round alone, and merges again with the rounds it kept.
  const std::string id = cfg.jobs[1].id;
  std::filesystem::remove(d.file("out/rounds/" + id + ".round3.json"));
  std::filesystem::remove(d.file("out/runs/" + id + ".json"));
  options.resume = true;
  RoundsExecutor again({1, 1, 900});
  const SuiteRunSummary r = run_suite(cfg, cfg.jobs, options, again);
  ASSERT_EQ(again.submitted.size(), 1u);
  EXPECT_EQ(again.submitted[0], std::make_pair(3, id));
  EXPECT_EQ(r.recorded, 4u);
  EXPECT_EQ(r.resumed, 3u);
  nlohmann::json merged;
  ASSERT_TRUE(read_result_file(d.file("out/runs/" + id + ".json"), &merged));
  EXPECT_EQ(merged["rounds"]["kept"], 3);
  EXPECT_EQ(merged["queries"]["throughput_qps"]["median"], 900);
  EXPECT_EQ(merged["rounds"]["by_round"][1]["throughput_qps"]["median"], 300);  // round 2, kept from before
}
