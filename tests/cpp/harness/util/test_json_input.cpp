// JSON read from files (json_input.hpp): malformed text, numbers beyond a double and nesting
// deep enough to overflow the stack of nlohmann's recursive copies and prints are refused by name,
// through each reader that takes JSON from elsewhere (result files, query-set sidecars).
#include <gtest/gtest.h>

#include <string>

#include "harness/core/query_set.hpp"
#include "harness/io/query_set_io.hpp"
#include "harness/run/result_set.hpp"
#include "harness/util/errors.hpp"
#include "harness/util/json_input.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {

std::string nested(int depth) { return std::string(std::size_t(depth), '[') + std::string(std::size_t(depth), ']'); }

}  // namespace

TEST(JsonInput, NestingUpToTheLimitIsAccepted) {
  const nlohmann::json j = parse_json_input(nested(kMaxJsonDepth), "j.json");
  const nlohmann::json* p = &j;
  int depth = 1;
  while (!p->empty()) p = &(*p)[0], ++depth;
  EXPECT_EQ(depth, kMaxJsonDepth);
  expect_input_error([] { parse_json_input(nested(kMaxJsonDepth + 1), "j.json"); }, "j.json",
                     "JSON nested deeper than 64 levels");
  expect_input_error([] { parse_json_input("{\"a\": " + nested(kMaxJsonDepth) + "}", "j.json"); }, "j.json",
                     "nested deeper");
}

TEST(JsonInput, MalformedTextAndHugeNumbersAreRefused) {
  expect_input_error([] { parse_json_input("{\"a\": }", "j.json"); }, "j.json", "malformed JSON");
  // nlohmann refuses a literal beyond a double with out_of_range, not parse_error.
  expect_input_error([] { parse_json_input("{\"a\": 1e999}", "j.json"); }, "j.json", "malformed JSON");
}

// 200,000 levels (a 400 KB file) crashed `bvhbench compare` and `bvhbench run` (its sidecar)
// with a stack overflow before the limit (found in review, confirmed by hand).
TEST(JsonInput, DeepFilesAreRefusedByTheirReaders) {
  TmpDir dir;
  const std::string deep = nested(200000);
  const std::string result = dir.file("r.json");
  write_file_bytes(result, "{\"schema\": \"bvhbench.result/1\", \"status\": \"ok\", \"job\": {\"method\": \"m\"}, "
                           "\"accuracy\": {\"x\": " + deep + "}}");
  expect_input_error([&] { load_result_set(result); }, result, "nested deeper");
  const std::string points = dir.file("q.xyz");
  write_file_bytes(points, "1 2 3\n");
  write_file_bytes(dir.file("q.json"), "{\"kind\": \"file\", \"n\": 1, \"seed\": " + deep + "}");
  expect_input_error([&] { load_query_set(points); }, dir.file("q.json"), "nested deeper");
}
