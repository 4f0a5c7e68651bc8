// Suite files (suite.hpp: parse_suite / load_suite): what the runner relies on is checked when
// the suite is read, and a malformed value anywhere is an InputError naming the file, never a
// yaml-cpp exception or a message without the file.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>

#include "harness/core/registry.hpp"
#include "harness/run/suite.hpp"
#include "harness/util/errors.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {

/// A one-matrix suite with `methods` and `query` as given (YAML flow values).
std::string suite(const std::string& methods, const std::string& query = "[inside]", const std::string& head = "") {
  return head + "matrices:\n  - meshes: [m.ply]\n    queries: [random]\n    query: " + query + "\n    methods: " + methods +
         "\n";
}

}  // namespace

TEST(SuiteParse, AGoodSuiteExpands) {
  const SuiteConfig cfg = parse_suite(suite("[brute_force, {name: ebp_octree, params: {leaf_factor: [3, 5]}}]",
                                            "[inside, distance]", "repeat: 2\nmemory_limit_mb: 0\n"),
                                      "dir/s.yml");
  EXPECT_EQ(cfg.repeat, 2);
  EXPECT_EQ(cfg.memory_limit_mb, 0);
  ASSERT_EQ(cfg.jobs.size(), 6u);
  EXPECT_EQ(cfg.jobs[0].id, "m__random-n10000-s1__inside__brute_force");
  EXPECT_EQ(cfg.jobs[0].mesh.path, "dir/m.ply");
  EXPECT_EQ(cfg.jobs[1].method.text, "ebp_octree:leaf_factor=3");
}

// A map or a list where a string is read: yaml-cpp's BadConversion escaped (found by fuzz_suite).
TEST(SuiteParse, ValuesOfTheWrongShapeAreRefused) {
  expect_input_error([] { parse_suite(suite("[brute_force]", "[{inside: 1}]"), "s.yml"); }, "s.yml",
                     "bad value: yaml-cpp: error at line 4");
  expect_input_error([] { parse_suite(suite("[{name: brute_force, params: {[a]: 1}}]"), "s.yml"); }, "s.yml",
                     "bad value");
  expect_input_error(
      [] { parse_suite("matrices:\n  - meshes: [{path: {a: b}}]\n    queries: [random]\n    methods: [x]\n", "s.yml"); },
      "s.yml", "bad value: yaml-cpp: error at line 2");
}

// A method spec that is not NAME:k=v was refused without the file's name and with its bytes
// unescaped (found by fuzz_suite).
TEST(SuiteParse, AMalformedMethodSpecNamesTheFile) {
  expect_input_error([] { parse_suite(suite("[\"brute_force:winding_threshold\"]"), "s.yml"); }, "s.yml",
                     "'winding_threshold' is not key=value (line 5)");
  expect_input_error([] { parse_suite(suite("[\"fault:mode=none,mode=none\"]"), "s.yml"); }, "s.yml",
                     "'mode' given twice");
}

// The child's address-space limit is set from memory_limit_mb (found in review).
TEST(SuiteParse, TheMemoryLimitIsANumberOfMiBFromZero) {
  for (const char* bad : {"-1", ".inf", ".nan"})
    expect_input_error([&] { parse_suite(suite("[brute_force]", "[inside]", std::string("memory_limit_mb: ") + bad + "\n"), "s.yml"); },
                       "s.yml", "memory_limit_mb must be a number of MiB >= 0");
  EXPECT_EQ(parse_suite(suite("[brute_force]", "[inside]", "memory_limit_mb: 1e300\n"), "s.yml").memory_limit_mb, 1e300);
}

// A few hundred bytes can ask for millions of jobs (a sweep of seven parameters, a matrix aliased
// many times): refused before they are listed (found in review; 324 bytes of sweeps took 2 s and
// 80,000 jobs, one parameter more would take minutes and gigabytes).
TEST(SuiteParse, ASuiteOfMillionsOfJobsIsRefused) {
  const std::string ten = "[1, 2, 3, 4, 5, 6, 7, 8, 9, 10]";
  const std::string sweep = "[{name: ebp_octree, params: {leaf_factor: " + ten + ", max_planes: " + ten +
                            ", cluster_angle: " + ten + ", cache_mb: " + ten + ", store: " + ten + ", coherent: [true, false]}}]";
  expect_input_error([&] { parse_suite(suite(sweep), "s.yml"); }, "s.yml", "more than 100000 variants");
  std::string matrices =
      "_m: &m {meshes: [a, b, c, d, e, f, g, h, i, j], queries: [random, near], methods: [brute_force, ebp_octree, fault]}\n"
      "matrices: [";
  for (int i = 0; i < 2000; ++i) matrices += i ? ", *m" : "*m";
  expect_input_error([&] { parse_suite(matrices + "]\n", "s.yml"); }, "s.yml", "expands to more than 100000 jobs");
  // Below the limit, duplicates are dropped as before.
  EXPECT_EQ(parse_suite("_m: &m {meshes: [a], queries: [random], methods: [brute_force]}\nmatrices: [*m, *m]\n", "s.yml").jobs.size(),
            2u);
}

// The thread axis: `threads:` of a matrix, a count or a list; one job per count, and a job on
// more than one thread has "__t<T>" at the end of its id (one thread keeps the id it had).
TEST(SuiteParse, TheThreadAxisMakesOneJobPerThreadCount) {
  const SuiteConfig cfg = parse_suite(
      "matrices:\n  - meshes: [m.ply]\n    queries: [random]\n    query: [inside]\n    methods: [brute_force]\n"
      "    threads: [1, 2, 4, 2]\n",
      "s.yml");
  ASSERT_EQ(cfg.jobs.size(), 3u);  // the repeated 2 once
  EXPECT_EQ(cfg.jobs[0].threads, 1);
  EXPECT_EQ(cfg.jobs[0].id, "m__random-n10000-s1__inside__brute_force");
  EXPECT_EQ(cfg.jobs[1].threads, 2);
  EXPECT_EQ(cfg.jobs[1].id, "m__random-n10000-s1__inside__brute_force__t2");
  EXPECT_EQ(cfg.jobs[2].id, "m__random-n10000-s1__inside__brute_force__t4");
  const SuiteConfig one = parse_suite(suite("[brute_force]"), "s.yml");
  ASSERT_EQ(one.jobs.size(), 1u);
  EXPECT_EQ(one.jobs[0].threads, 1);
  const SuiteConfig scalar = parse_suite(suite("[brute_force]") + "    threads: 8\n", "s.yml");
  ASSERT_EQ(scalar.jobs.size(), 1u);
  EXPECT_EQ(scalar.jobs[0].threads, 8);
  for (const char* bad : {"0", "-2", "1025", "two", "[]", "{a: 1}"})
    expect_input_error([&] { parse_suite(suite("[brute_force]") + "    threads: " + bad + "\n", "s.yml"); }, "s.yml",
                       "threads");
}

// `methods: all` is every registered method but the testing-only ones, each with the sweep its
// registration declares; `except:` leaves some out and must name methods.
TEST(SuiteParse, MethodsAllIsEveryMethodWithItsOwnSweep) {
  const SuiteConfig cfg = parse_suite(suite("all", "[inside]"), "s.yml");
  std::vector<std::string> specs;
  for (const JobPlan& j : cfg.jobs) specs.push_back(j.method.text);
  EXPECT_EQ(specs, Registry::global().all_method_specs());
  EXPECT_NE(std::find(specs.begin(), specs.end(), "brute_force"), specs.end());
  EXPECT_EQ(std::find(specs.begin(), specs.end(), "fault"), specs.end());
  for (const MethodInfo& m : Registry::global().methods()) {
    if (m.testing_only) continue;
    for (const std::string& entry : m.sweep)
      EXPECT_NE(std::find(specs.begin(), specs.end(), entry.empty() ? m.name : m.name + ":" + entry), specs.end())
          << m.name << ":" << entry;
  }
  const SuiteConfig some = parse_suite(suite("[{all: true, except: [brute_force]}, brute_force]", "[inside]"), "s.yml");
  EXPECT_EQ(some.jobs.size(), cfg.jobs.size());  // brute_force is back once, by name
  expect_input_error([] { parse_suite(suite("[{all: true, except: [no_such]}]"), "s.yml"); }, "s.yml",
                     "except: names no method: 'no_such'");
  expect_input_error([] { parse_suite(suite("[{all: true, only: [x]}]"), "s.yml"); }, "s.yml", "unknown key 'only'");
}

// `rounds:` (suites/README.md, "Rounds"): times every job runs, 1 by default; a bad value is
// refused with the file, its line and the value given.
TEST(SuiteParse, RoundsIsACountFromOneWithItsLineAndValueWhenBad) {
  EXPECT_EQ(parse_suite(suite("[brute_force]"), "s.yml").rounds, 1);
  EXPECT_EQ(parse_suite(suite("[brute_force]", "[inside]", "rounds: 3\n"), "s.yml").rounds, 3);
  EXPECT_EQ(parse_suite(suite("[brute_force]", "[inside]", "rounds: 100\n"), "s.yml").rounds, 100);
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"0", "rounds must be an integer from 1 to 100, not 0 (line 2)"},
      {"-2", "rounds must be an integer from 1 to 100, not -2 (line 2)"},
      {"101", "rounds must be an integer from 1 to 100, not 101 (line 2)"},
      {"x", "not 'x' (line 2)"},
      {"2.5", "not '2.5' (line 2)"},
      {"true", "not 'true' (line 2)"},
      {"[2]", "not a list or a map (line 2)"},
      {"{n: 2}", "not a list or a map (line 2)"}};
  for (const auto& [value, message] : bad) {  // on line 2, after the name
    SCOPED_TRACE(value);
    expect_input_error([&] { parse_suite("name: s\nrounds: " + value + "\n" + suite("[brute_force]"), "dir/s.yml"); },
                       "dir/s.yml", message);
  }
  // A misspelt key is caught by the grammar like any other.
  expect_input_error([] { parse_suite("round: 2\n" + suite("[brute_force]"), "s.yml"); }, "s.yml",
                     "did you mean 'rounds'?");
}
