// Mann-Whitney U against reference p-values, the calibration kernel, and compare's verdicts on
// small in-memory result sets. Reference values were computed offline with SciPy 1.17
// (scipy.stats.mannwhitneyu) and, where there are ties, by enumerating every permutation.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "harness/run/calibration.hpp"
#include "harness/run/compare.hpp"
#include "harness/run/mann_whitney.hpp"

using namespace bvhbench;
using json = nlohmann::json;

namespace {

void expect_rel_near(double got, double want, double rel) {
  EXPECT_NEAR(got, want, rel * std::fabs(want)) << "got " << got << ", want " << want;
}

}  // namespace

// ---- exact distribution, no ties: equal to scipy method="exact" ----------------------------

TEST(MannWhitney, ExactFullySeparatedFiveByFive) {
  // The smallest two-sided p with 5 per side: 2 / C(10, 5).
  MannWhitney r = mann_whitney_u({1, 2, 3, 4, 5}, {6, 7, 8, 9, 10});
  EXPECT_TRUE(r.exact);
  EXPECT_DOUBLE_EQ(r.u1, 0.0);
  EXPECT_DOUBLE_EQ(r.u, 25.0);
  expect_rel_near(r.p_value, 0.007936507936507936, 1e-12);
  // Symmetric in the order of the samples.
  MannWhitney s = mann_whitney_u({6, 7, 8, 9, 10}, {1, 2, 3, 4, 5});
  EXPECT_DOUBLE_EQ(s.u1, 25.0);
  expect_rel_near(s.p_value, r.p_value, 1e-12);
}

TEST(MannWhitney, ExactSixByFiveOverlapping) {
  MannWhitney r = mann_whitney_u({1.1, 2.3, 3.5, 4.2, 6.0, 7.7}, {2.0, 5.1, 5.5, 8.0, 9.1});
  EXPECT_TRUE(r.exact);
  EXPECT_DOUBLE_EQ(r.u1, 9.0);
  expect_rel_near(r.p_value, 0.32900432900432897, 1e-12);
}

TEST(MannWhitney, ExactNineByNine) {
  MannWhitney r = mann_whitney_u({10.2, 11.5, 9.8, 10.9, 12.1, 10.4, 11.0, 9.5, 10.7},
                                 {12.3, 11.9, 13.4, 12.8, 11.2, 13.0, 12.5, 14.1, 12.0});
  EXPECT_TRUE(r.exact);
  EXPECT_DOUBLE_EQ(r.u1, 4.0);
  expect_rel_near(r.p_value, 0.0004936240230357877, 1e-12);
}

TEST(MannWhitney, ExactTinySamplesCannotReject) {
  MannWhitney r = mann_whitney_u({3.0}, {1.0, 2.0, 4.0});
  EXPECT_DOUBLE_EQ(r.u1, 2.0);
  EXPECT_DOUBLE_EQ(r.p_value, 1.0);
}

// ---- exact distribution with ties: the permutation distribution of the mid-rank sums -----------

TEST(MannWhitney, ExactWithTiesIsThePermutationDistribution) {
  // Enumerating all C(11, 6) = 462 splits of the mid-ranks gives 52/462. (scipy's
  // method="exact" uses the no-ties table here and reports 0.1255.)
  MannWhitney r = mann_whitney_u({1, 2, 2, 3, 3, 3}, {2, 3, 4, 4, 5});
  EXPECT_TRUE(r.exact);
  EXPECT_DOUBLE_EQ(r.u1, 5.5);
  expect_rel_near(r.p_value, 0.11255411255411256, 1e-12);
}

TEST(MannWhitney, AllEqualIsNotSignificant) {
  EXPECT_DOUBLE_EQ(mann_whitney_u({2, 2, 2, 2, 2}, {2, 2, 2, 2, 2}).p_value, 1.0);
  EXPECT_DOUBLE_EQ(mann_whitney_u(std::vector<double>(30, 2.0), std::vector<double>(30, 2.0)).p_value, 1.0);
}

TEST(MannWhitney, EmptySampleIsNotSignificant) {
  EXPECT_DOUBLE_EQ(mann_whitney_u({}, {1, 2, 3}).p_value, 1.0);
}

// ---- normal approximation with tie correction: scipy method="asymptotic" -----------------------

TEST(MannWhitney, AsymptoticLargeSamplesWithTies) {
  std::vector<double> x = {10.0, 10.3, 9.7, 9.1, 9.5, 9.0, 10.1, 11.3, 9.5, 9.4, 10.5, 10.4, 10.1,
                           9.1, 10.0, 10.7, 8.7, 9.5, 8.1, 8.7, 8.2, 9.8, 8.7, 10.3, 10.2};
  std::vector<double> y = {10.4, 8.1, 10.1, 10.6, 10.7, 9.1, 10.1, 9.6, 9.8, 11.7, 9.8, 10.6, 11.5, 10.0, 10.5,
                           10.7, 10.7, 9.4, 10.7, 12.0, 9.1, 11.5, 10.7, 10.0, 12.6, 11.4, 9.4, 10.7, 11.2, 10.4};
  MannWhitney r = mann_whitney_u(x, y);  // 25 and 30 > kMannWhitneyExactMax
  EXPECT_FALSE(r.exact);
  EXPECT_DOUBLE_EQ(r.u1, 189.0);
  expect_rel_near(r.p_value, 0.001679017764348307, 1e-9);
}

TEST(MannWhitney, AsymptoticHeavyTies) {
  std::vector<double> x, y;
  for (int i = 0; i < 5; ++i) x.push_back(1);
  for (int i = 0; i < 10; ++i) x.push_back(2);
  for (int i = 0; i < 10; ++i) x.push_back(3);
  for (int i = 0; i < 8; ++i) y.push_back(2);
  for (int i = 0; i < 12; ++i) y.push_back(3);
  for (int i = 0; i < 5; ++i) y.push_back(4);
  MannWhitney r = mann_whitney_u(x, y);
  EXPECT_FALSE(r.exact);
  EXPECT_DOUBLE_EQ(r.u1, 180.0);
  expect_rel_near(r.p_value, 0.005934137970790045, 1e-9);
}

TEST(MannWhitney, TwentyByTwentyBothWays) {
  // At the switch-over size both methods are available; in the far tail the normal
  // approximation is conservative (scipy: exact 6.9e-6, asymptotic 2.9e-5).
  std::vector<double> x, y;
  for (int i = 0; i < 20; ++i) {
    x.push_back(100 + 3 * i);
    y.push_back(131 + 3 * i);
  }
  MannWhitney e = mann_whitney_u(x, y);  // 20 per side: still exact
  MannWhitney a = mann_whitney_u(x, y, false, /*force_asymptotic=*/true);
  EXPECT_TRUE(e.exact);
  EXPECT_FALSE(a.exact);
  EXPECT_DOUBLE_EQ(e.u1, 45.0);
  EXPECT_DOUBLE_EQ(a.u1, 45.0);
  expect_rel_near(e.p_value, 6.91365976465362e-06, 1e-9);
  expect_rel_near(a.p_value, 2.9248649327368934e-05, 1e-9);
}

// ---- calibration kernel ---------------------------------------------------------------------

TEST(Calibration, KernelIsDeterministic) {
  EXPECT_EQ(calibration_kernel(1024, 100000), calibration_kernel(1024, 100000));
  EXPECT_NE(calibration_kernel(1024, 100000), calibration_kernel(1024, 100001));
}

TEST(Calibration, BlockHasSamplesAndMedian) {
  json c = measure_calibration(3);
  EXPECT_EQ(c["kernel"], kCalibrationKernel);
  ASSERT_EQ(c["kernel_seconds"].size(), 3u);
  EXPECT_GT(c["median_seconds"].get<double>(), 0.0);
  EXPECT_LE(c["min_seconds"].get<double>(), c["median_seconds"].get<double>());
}

// ---- verdicts on in-memory result sets ---------------------------------------------------------

namespace {

json result(const std::string& method, std::vector<double> qps, double cal_s, double nodes = 12.5) {
  json r = {{"schema", "bvhbench.result/1"},
            {"context", {{"host", "h"}, {"git_commit", "abc"}}},
            {"job",
             {{"id", "cow__random__inside__" + method},
              {"method", method},
              {"params", json::object()},
              {"params_key", ""},
              {"query", "inside"},
              {"mesh", {{"name", "cow"}, {"sha256", "aa"}}},
              {"queries", {{"kind", "random"}, {"sha256", "bb"}, {"n", 1000}}}}},
            {"status", "ok"},
            {"message", ""},
            {"queries", {{"throughput_qps", {{"samples", qps}}}}},
            {"counters", {{"nodes_visited", nodes}}},
            {"accuracy", {{"inside", {{"wrong", 0}, {"rate", 0.0}}}}},
            {"calibration", {{"kernel", kCalibrationKernel}, {"median_seconds", cal_s}}}};
  return r;
}

ResultSet set_of(std::vector<json> rs) {
  ResultSet s;
  s.path = "mem";
  for (auto& r : rs) {
    s.files.push_back("mem");
    s.results.push_back(r);
  }
  return s;
}

const std::vector<double> kQps = {1000, 1010, 990, 1005, 995, 1002, 998, 1008, 992};

std::vector<double> scaled(const std::vector<double>& v, double k) {
  std::vector<double> o;
  for (double x : v) o.push_back(x * k);
  return o;
}

}  // namespace

TEST(Compare, IdenticalIsUnchanged) {
  json rep = compare_result_sets(set_of({result("m", kQps, 0.03)}), set_of({result("m", kQps, 0.03)}), {});
  EXPECT_EQ(rep["exit_code"], 0);
  EXPECT_EQ(rep["pairs"][0]["verdict"], "unchanged");
}

TEST(Compare, SlowerMachineIsUnchanged) {
  // Half the speed, and the calibration kernel takes twice as long: the same method.
  json rep = compare_result_sets(set_of({result("m", kQps, 0.03)}), set_of({result("m", scaled(kQps, 0.5), 0.06)}), {});
  EXPECT_EQ(rep["exit_code"], 0);
  EXPECT_EQ(rep["pairs"][0]["verdict"], "unchanged");
}

TEST(Compare, TwoTimesSlowerRegresses) {
  json rep = compare_result_sets(set_of({result("m", kQps, 0.03)}), set_of({result("m", scaled(kQps, 0.5), 0.03)}), {});
  EXPECT_EQ(rep["exit_code"], 1);
  EXPECT_EQ(rep["pairs"][0]["verdict"], "regressed");
  CompareOptions report_only;
  report_only.timing_gates = false;
  rep = compare_result_sets(set_of({result("m", kQps, 0.03)}), set_of({result("m", scaled(kQps, 0.5), 0.03)}), report_only);
  EXPECT_EQ(rep["exit_code"], 0);
  EXPECT_EQ(rep["pairs"][0]["verdict"], "regressed");
  EXPECT_FALSE(rep["pairs"][0]["gates"].get<bool>());
}

TEST(Compare, CounterChangeGatesEvenInReportMode) {
  CompareOptions report_only;
  report_only.timing_gates = false;
  json rep = compare_result_sets(set_of({result("m", kQps, 0.03)}), set_of({result("m", kQps, 0.03, 12.6)}), report_only);
  EXPECT_EQ(rep["exit_code"], 1);
  EXPECT_EQ(rep["pairs"][0]["reasons"][0]["code"], "counters_changed");
}

TEST(Compare, MissingNewAndFailed) {
  json failed = result("a", kQps, 0.03);
  failed["status"] = "crash";
  json rep = compare_result_sets(set_of({result("a", kQps, 0.03), result("b", kQps, 0.03)}),
                                 set_of({failed, result("c", kQps, 0.03)}), {});
  EXPECT_EQ(rep["exit_code"], 1);
  EXPECT_EQ(rep["summary"]["failed"], 1);
  EXPECT_EQ(rep["summary"]["missing"], 1);
  EXPECT_EQ(rep["summary"]["new"], 1);
}

// What the report quotes from a result is cut at a byte count: a cut inside a UTF-8 sequence is
// escaped, so that the JSON report still prints; a job's n that is a float beyond long long is
// shown as it is, not converted (undefined). Found in review, confirmed with fuzz_compare.
TEST(Compare, QuotedValuesKeepTheReportPrintable) {
  json a = result("m", kQps, 0.03), b = result("m", kQps, 0.03);
  a["job"]["mesh"]["sha256"] = "0123456789abcde\xC3\xA9";  // the 16th byte starts "é"
  a["context"]["git_commit"] = "0123456789a\xC3\xA9";      // the 12th byte too
  json rep = compare_result_sets(set_of({a}), set_of({b}), {});
  ASSERT_NO_THROW((void)rep.dump());
  EXPECT_EQ(rep["pairs"][0]["reasons"][0]["detail"], "mesh sha256 0123456789abcde\\xC3 -> aa");
  EXPECT_EQ(rep["base"]["commits"][0], "0123456789a\\xC3");
  json c = result("m", kQps, 0.03);
  c["job"].erase("id");
  c["job"]["queries"]["n"] = 1e300;
  rep = compare_result_sets(set_of({c}), set_of({c}), {});
  EXPECT_EQ(rep["pairs"][0]["job"], "cow__random-n1e+300__inside__m");
}
