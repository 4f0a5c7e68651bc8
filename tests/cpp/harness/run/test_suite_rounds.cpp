// A suite run in rounds (run/suite_rounds.hpp): where each round keeps its files (one round keeps
// the layout a suite always had), what --resume counts as done, the order of a round's
// structures, and the book that says when a job has all its rounds.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "harness/run/run_job.hpp"
#include "harness/run/suite_rounds.hpp"
#include "harness/util/atomic_file.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;
using json = nlohmann::json;

namespace {

JobPlan job(const std::string& id, const std::string& mesh) {
  JobPlan j;
  j.id = id;
  j.mesh.name = mesh;
  j.mesh.path = mesh + ".ply";
  return j;
}

json row(const std::string& code, double median = 0) {
  JobSpec spec;
  json r = make_result(spec, code, "");
  if (code == status::ok) r["queries"] = {{"throughput_qps", {{"median", median}}}};
  return r;
}

std::vector<std::string> group_ids(const std::vector<BuildGroup>& groups) {
  std::vector<std::string> ids;
  for (const BuildGroup& g : groups) ids.push_back(g.id);
  return ids;
}

}  // namespace

TEST(SuiteRounds, OneRoundKeepsTheLayoutASuiteAlwaysHad) {
  const JobPlan j = job("m__random-n10-s1__inside__brute_force", "m");
  const RoundFiles one = round_files("out", j, 1, 1);
  EXPECT_EQ(one.result, "out/runs/" + j.id + ".json");
  EXPECT_EQ(one.child, "out/runs/" + j.id + ".json.child");
  EXPECT_EQ(one.log, "out/logs/" + j.id + ".log");
  EXPECT_EQ(group_round_files("out", "m__brute_force", 1, 1).plan, "out/logs/m__brute_force.plan.json");
  EXPECT_EQ(group_round_files("out", "m__brute_force", 1, 1).built, "out/logs/m__brute_force.built.json");
}

// Round files stay out of runs/, which every reader of a result folder takes for the jobs.
TEST(SuiteRounds, EachRoundHasFilesOfItsOwnOutsideRuns) {
  const JobPlan j = job("m__random-n10-s1__inside__brute_force", "m");
  const RoundFiles second = round_files("out", j, 2, 3);
  EXPECT_EQ(second.result, "out/rounds/" + j.id + ".round2.json");
  EXPECT_EQ(second.child, "out/rounds/" + j.id + ".round2.json.child");
  EXPECT_EQ(second.log, "out/logs/" + j.id + ".round2.log");
  EXPECT_NE(round_files("out", j, 1, 3).result, second.result);
  EXPECT_EQ(group_round_files("out", "m__brute_force", 3, 3).plan, "out/logs/m__brute_force.round3.plan.json");
}

TEST(SuiteRounds, ARoundIsDoneWhenItsResultIsThereAndRan) {
  TmpDir d;
  const JobPlan j = job("j", "m");
  std::filesystem::create_directories(d.file("out/rounds"));
  EXPECT_FALSE(round_done(d.file("out"), j, 1, 2));
  write_json_atomic(round_files(d.file("out"), j, 1, 2).result, row(status::crash));
  EXPECT_TRUE(round_done(d.file("out"), j, 1, 2));   // a failure is a round done: its status is its result
  EXPECT_FALSE(round_done(d.file("out"), j, 2, 2));  // the other round is not
  write_json_atomic(round_files(d.file("out"), j, 2, 2).result, row(status::not_run));
  EXPECT_FALSE(round_done(d.file("out"), j, 2, 2));  // its child died in another job: run it again
  write_json_atomic(round_files(d.file("out"), j, 2, 2).child, row(status::ok, 1));
  std::filesystem::remove(round_files(d.file("out"), j, 2, 2).result);
  EXPECT_TRUE(round_done(d.file("out"), j, 2, 2));  // a child's result left behind is adopted
}

// Two matrices over the same meshes: the structures come mesh by mesh, and alternate on a mesh.
TEST(SuiteRounds, ARoundRunsMeshAfterMeshAlternatingTheStructuresOfEach) {
  TmpDir d;
  write_file_bytes(d.file("s.yml"), "truth: false\nmatrices:\n"
                                    "  - {meshes: [a.ply, b.ply], queries: [random], query: [inside], methods: [brute_force]}\n"
                                    "  - {meshes: [a.ply, b.ply], queries: [random], query: [inside], methods: [fault]}\n");
  const SuiteConfig cfg = load_suite(d.file("s.yml"));
  const std::vector<BuildGroup> groups = group_by_structure(cfg.jobs);
  ASSERT_EQ(group_ids(groups), (std::vector<std::string>{"a__brute_force", "b__brute_force", "a__fault", "b__fault"}));
  EXPECT_EQ(group_ids(round_order(groups, cfg.jobs, 1)),
            (std::vector<std::string>{"a__brute_force", "a__fault", "b__brute_force", "b__fault"}));
  EXPECT_EQ(group_ids(round_order(groups, cfg.jobs, 2)),
            (std::vector<std::string>{"a__fault", "a__brute_force", "b__fault", "b__brute_force"}));
  EXPECT_EQ(group_ids(round_order(groups, cfg.jobs, 3)), group_ids(round_order(groups, cfg.jobs, 1)));
}

TEST(SuiteRounds, TheBookMergesAJobOnceItHasEveryRound) {
  RoundBook book(3);
  EXPECT_FALSE(book.add(4, 2, row(status::ok, 30), true));
  EXPECT_FALSE(book.add(0, 1, row(status::ok, 5), false));  // another job: its own rounds
  EXPECT_FALSE(book.add(4, 1, row(status::ok, 10), false));
  EXPECT_FALSE(book.add(4, 1, row(status::ok, 11), false));  // a round given twice counts once
  const std::optional<RoundBook::Complete> done = book.add(4, 3, row(status::crash), false);
  ASSERT_TRUE(done);
  EXPECT_FALSE(done->resumed);  // round 2 ran now
  EXPECT_EQ(done->result["rounds"]["kept"], 2);
  EXPECT_EQ(done->result["rounds"]["by_round"][0]["throughput_qps"]["median"], 11);
  EXPECT_FALSE(book.add(0, 2, row(status::ok, 5), false));
  const std::optional<RoundBook::Complete> resumed = book.add(0, 3, row(status::ok, 5), false);
  ASSERT_TRUE(resumed);
  EXPECT_TRUE(resumed->resumed);  // every round from an earlier run
  EXPECT_THROW(book.add(0, 4, row(status::ok), true), std::logic_error);
}

// One round: the round's result is the job's, as it always was, with no record of rounds.
TEST(SuiteRounds, WithOneRoundTheBookGivesTheResultUnchanged) {
  RoundBook book(1);
  const json r = row(status::ok, 7);
  const std::optional<RoundBook::Complete> done = book.add(0, 1, r, true);
  ASSERT_TRUE(done);
  EXPECT_EQ(done->result, r);
  EXPECT_FALSE(done->result.contains("rounds"));
}
