// The result schema compiled into the runner (harness/run/result_schema.json): what validate()
// refuses and allows, how describe() matches wildcards, and that a result made by the runner's own
// make_result() (the skeleton of every status row) follows it. The Python side
// (tests/python/harness/test_result_schema.py) checks whole suites' results against the same file.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "harness/core/registry.hpp"
#include "harness/run/result_schema.hpp"
#include "harness/run/run_job.hpp"
#include "harness/run/summary_csv.hpp"
#include "harness/util/errors.hpp"

using namespace bvhbench;
using json = nlohmann::json;

namespace {

std::string refusal(const json& r) {
  try {
    ResultSchema::get().validate(r, "r.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

json status_row() {
  JobSpec spec;
  spec.mesh_path = "m.ply";
  spec.queries_path = "q.npy";
  spec.method = Registry::global().resolve("brute_force");
  return make_result(spec, status::crash, "killed by signal 11");
}

}  // namespace

TEST(ResultSchema, CompiledSchemaIsTheFilesVersion) {
  const ResultSchema& s = ResultSchema::get();
  EXPECT_EQ(s.version(), "bvhbench.result/1");
  EXPECT_GT(s.fields().size(), 100u);
  ASSERT_FALSE(s.summary_columns().empty());
  EXPECT_EQ(s.summary_columns().front().column, "job_id");
}

// One home for the job statuses: the schema's enum. The runner's names are those, in that order,
// and a result with another status is refused.
TEST(ResultSchema, StatusesAreTheSchemasEnum) {
  const std::vector<std::string>& in_schema = ResultSchema::get().statuses();
  ASSERT_EQ(in_schema.size(), std::size(status::all));
  for (std::size_t i = 0; i < in_schema.size(); ++i) EXPECT_EQ(in_schema[i], status::all[i]);
  json r = status_row();
  r["status"] = "exploded";
  EXPECT_NE(refusal(r).find("status 'exploded' is none of: ok, unsupported"), std::string::npos) << refusal(r);
}

TEST(ResultSchema, DescribeMatchesExactThenWildcardThenFreeForm) {
  const ResultSchema& s = ResultSchema::get();
  ASSERT_NE(s.describe({"queries", "latency_ns", "p99"}), nullptr);
  EXPECT_EQ(s.describe({"queries", "latency_ns", "p99"})->path, "queries.latency_ns.p99");
  ASSERT_NE(s.describe({"counters", "nodes_visited"}), nullptr);
  EXPECT_EQ(s.describe({"counters", "nodes_visited"})->path, "counters.*");
  ASSERT_NE(s.describe({"structure", "levels", "deep", "er"}), nullptr);
  EXPECT_EQ(s.describe({"structure", "levels", "deep", "er"})->path, "structure.*");
  EXPECT_EQ(s.describe({"job", "colour"}), nullptr);
  EXPECT_EQ(s.describe({"counters", "x", "y"}), nullptr);  // counters.* is a number, not an object
  EXPECT_EQ(s.describe({}), nullptr);
}

TEST(ResultSchema, StatusRowSkeletonFollowsTheSchema) {
  const json r = status_row();
  EXPECT_EQ(refusal(r), "");
  EXPECT_EQ(ResultSchema::get().undescribed(r), std::vector<std::string>{});
}

TEST(ResultSchema, RefusesWrongTypesAndMissingFieldsNamingThem) {
  json r = status_row();
  r["context"]["cores"] = 2.5;
  EXPECT_NE(refusal(r).find("r.json: context.cores must be an integer"), std::string::npos) << refusal(r);

  r = status_row();
  r["context"].erase("host");
  EXPECT_NE(refusal(r).find("result without context.host"), std::string::npos) << refusal(r);

  r = status_row();
  r["job"]["params"]["leaf_factor"] = 5;
  EXPECT_NE(refusal(r).find("job.params.leaf_factor must be a string"), std::string::npos) << refusal(r);

  r = status_row();
  r["schema"] = "bvhbench.result/9";
  EXPECT_NE(refusal(r).find("unknown result schema 'bvhbench.result/9'"), std::string::npos) << refusal(r);

  EXPECT_NE(refusal(json::array()).find("not a bvhbench result"), std::string::npos);
}

TEST(ResultSchema, OkResultsNeedTheirBlocksStatusRowsDoNot) {
  json r = status_row();
  EXPECT_EQ(refusal(r), "");       // a crash has no build, queries, memory
  r["status"] = "ok";
  EXPECT_NE(refusal(r).find("(status ok)"), std::string::npos) << refusal(r);
}

TEST(ResultSchema, NewFieldsAreAllowedButReportedAsUndescribed) {
  json r = status_row();
  r["job"]["colour"] = "red";
  r["counters"] = {{"nodes_visited", 3.5}};
  EXPECT_EQ(refusal(r), "");
  EXPECT_EQ(ResultSchema::get().undescribed(r), std::vector<std::string>{"job.colour"});
}

TEST(ResultSchema, ArraysAreCheckedItemByItem) {
  json r = status_row();
  r["machine_dependent"] = {{"counters", {"triangles_tested", 3}}, {"fingerprint", json::object()}};
  EXPECT_NE(refusal(r).find("machine_dependent.counters must be an array of strings"), std::string::npos)
      << refusal(r);
  r["machine_dependent"]["counters"] = {"triangles_tested"};
  EXPECT_EQ(refusal(r), "");
}

TEST(ResultSchema, ParseRefusesAMalformedSchema) {
  EXPECT_THROW(ResultSchema::parse("{"), std::invalid_argument);
  EXPECT_THROW(ResultSchema::parse(R"({"schema": "x", "fields": {"a": {}}, "summary_csv": []})"),
               std::invalid_argument);
}

TEST(SummaryCsv, ColumnsAreTheSchemasAndCellsFollowItsRules) {
  std::vector<std::string> want;
  for (const SummaryColumn& c : ResultSchema::get().summary_columns()) want.push_back(c.column);
  EXPECT_EQ(summary_header(), want);

  json r = status_row();
  r["status"] = "ok";
  r["job"]["mesh"]["triangles"] = 4;
  r["build"] = {{"structure_bytes", 10}};
  r["counters"] = {{"cache_hits", 3.0}, {"cache_misses", 1.0}};
  const std::vector<std::string> row = summary_row(r);
  ASSERT_EQ(row.size(), want.size());
  auto cell = [&](const std::string& column) {
    return row[std::size_t(std::find(want.begin(), want.end(), column) - want.begin())];
  };
  EXPECT_EQ(cell("mesh"), "m");                    // no name: the file stem of job.mesh.path
  EXPECT_EQ(cell("bytes_per_triangle"), "2.5");    // ratio
  EXPECT_EQ(cell("c_cache_hit_rate"), "0.75");     // share: hits / (hits + misses)
  EXPECT_EQ(cell("message"), "killed by signal 11");
  EXPECT_EQ(cell("qps_median"), "");               // absent: blank
}
