// The best of a job's rounds (run/round_merge.hpp): the round kept, whole, and the record of every
// round beside it, whatever mix of statuses the rounds ended in.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "harness/core/registry.hpp"
#include "harness/run/result_schema.hpp"
#include "harness/run/round_merge.hpp"
#include "harness/run/run_job.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using json = nlohmann::json;

namespace {

/// A round that ended ok at `median` queries/s, each of its other figures marked by `tag`, so
/// that a merged result shows whose figures it carries.
json ok_round(double median, int tag) {
  JobSpec spec;
  spec.mesh_path = "m.ply";
  spec.queries_path = "q.npy";
  spec.method = Registry::global().resolve("brute_force");
  json r = make_result(spec, status::ok, "");
  r["queries"] = {{"n", 100},
                  {"throughput_qps", {{"median", median}, {"min", median - 1}, {"max", median + 1},
                                      {"samples", {median - 1, median, median + 1}}}},
                  {"latency_ns", {{"p50", 100 + tag}, {"p99", 200 + tag}}}};
  r["build"] = {{"seconds", 0.5 + tag}, {"structure_bytes", 1000 + tag}};
  r["memory"] = {{"peak_rss_bytes", 5000 + tag}};
  r["elapsed_seconds"] = 1.0 + tag;
  return r;
}

json failed_round(const std::string& code, const std::string& message) {
  JobSpec spec;
  spec.mesh_path = "m.ply";
  spec.queries_path = "q.npy";
  spec.method = Registry::global().resolve("brute_force");
  return make_result(spec, code, message);
}

}  // namespace

TEST(RoundMerge, TheRoundOfTheHighestMedianIsKeptWhole) {
  const std::vector<json> rounds = {ok_round(1000, 1), ok_round(3000, 2), ok_round(2000, 3)};
  EXPECT_EQ(kept_round(rounds), 1u);
  const json merged = merge_rounds(rounds);
  // Every figure is round 2's: its latency, build and memory were measured beside its throughput.
  json without_record = merged;
  without_record.erase("rounds");
  EXPECT_EQ(without_record, rounds[1]);
  EXPECT_EQ(merged["queries"]["latency_ns"]["p99"], 202);
  EXPECT_EQ(merged["build"]["seconds"], 2.5);
  EXPECT_EQ(merged["memory"]["peak_rss_bytes"], 5002);
  // The record: every round's throughput, none hidden, and which one this is.
  EXPECT_EQ(merged["rounds"]["count"], 3);
  EXPECT_EQ(merged["rounds"]["kept"], 2);
  const json& by_round = merged["rounds"]["by_round"];
  ASSERT_EQ(by_round.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    SCOPED_TRACE(k);
    EXPECT_EQ(by_round[k]["round"], k + 1);
    EXPECT_EQ(by_round[k]["status"], "ok");
    EXPECT_EQ(by_round[k]["throughput_qps"], rounds[k]["queries"]["throughput_qps"]);
  }
}

TEST(RoundMerge, OfEqualMediansTheEarliestIsKept) {
  EXPECT_EQ(kept_round({ok_round(2000, 1), ok_round(2000, 2)}), 0u);
  EXPECT_EQ(kept_round({ok_round(1000, 1), ok_round(2000, 2), ok_round(2000, 3)}), 1u);
}

// An ok round without a median (no timed pass) is still ok, but any measured one beats it.
TEST(RoundMerge, AnOkRoundWithoutAMedianRanksBelowAMeasuredOne) {
  json unmeasured = ok_round(0, 1);
  unmeasured["queries"]["throughput_qps"]["median"] = nullptr;
  EXPECT_EQ(kept_round({unmeasured, ok_round(10, 2)}), 1u);
  EXPECT_EQ(kept_round({unmeasured, failed_round(status::crash, "killed by signal 11")}), 0u);
}

// One round crashed: the job is ok, its best ok round, and the crash is listed with its message.
TEST(RoundMerge, AFailedRoundIsListedBesideTheBestOkRound) {
  const std::vector<json> rounds = {ok_round(1000, 1), failed_round(status::crash, "killed by signal 11 (SIGSEGV)"),
                                    ok_round(1500, 3)};
  const json merged = merge_rounds(rounds);
  EXPECT_EQ(merged["status"], "ok");
  EXPECT_EQ(merged["rounds"]["kept"], 3);
  const json& crashed = merged["rounds"]["by_round"][1];
  EXPECT_EQ(crashed["status"], "crash");
  EXPECT_EQ(crashed["message"], "killed by signal 11 (SIGSEGV)");
  EXPECT_TRUE(crashed["throughput_qps"].is_null());
}

// No round ended ok: the job is its first failure of its own, not a `not_run` that another job caused.
TEST(RoundMerge, WithoutAnOkRoundTheFirstRealFailureIsTheJobsRow) {
  const std::vector<json> rounds = {failed_round(status::not_run, "not run: the child ... ended in job x"),
                                    failed_round(status::timeout, "killed after 5 s"),
                                    failed_round(status::crash, "killed by signal 11")};
  EXPECT_EQ(kept_round(rounds), 1u);
  const json merged = merge_rounds(rounds);
  EXPECT_EQ(merged["status"], "timeout");
  EXPECT_EQ(merged["message"], "killed after 5 s");
  EXPECT_EQ(merged["rounds"]["kept"], 2);
  EXPECT_EQ(merged["rounds"]["by_round"][2]["status"], "crash");
}

// Every round not run: the job stays not_run, so that `suite --resume` runs it again.
TEST(RoundMerge, AJobNeverRunStaysNotRun) {
  const json merged = merge_rounds({failed_round(status::not_run, "a"), failed_round(status::not_run, "b")});
  EXPECT_EQ(merged["status"], "not_run");
  EXPECT_EQ(merged["message"], "a");
  EXPECT_EQ(merged["rounds"]["kept"], 1);
}

// The record is described by the result schema: a merged result is a result like any other
// (rounds made of a real ok result of the report's fixture, and of status rows).
TEST(RoundMerge, AMergedResultFollowsTheResultSchema) {
  const json real = json::parse(
      test::read_file_bytes(std::string(BVHBENCH_FIXTURES_DIR) + "/results_small/runs/cow__random-n500-s1__inside__ebp_octree.json"));
  ASSERT_EQ(real["status"], "ok");
  json faster = real;
  faster["queries"]["throughput_qps"]["median"] = real["queries"]["throughput_qps"]["median"].get<double>() * 2;
  for (const json& merged : {merge_rounds({real, failed_round(status::oom, "std::bad_alloc"), faster}),
                             merge_rounds({failed_round(status::crash, "x"), failed_round(status::error, "y")})}) {
    EXPECT_NO_THROW(ResultSchema::get().validate(merged, "merged.json")) << merged.dump();
    EXPECT_EQ(ResultSchema::get().undescribed(merged), std::vector<std::string>());
  }
}

TEST(RoundMerge, NoRoundsIsAProgrammingError) { EXPECT_THROW(kept_round({}), std::logic_error); }
