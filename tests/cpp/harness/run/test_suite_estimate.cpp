// A suite's expected time (run/suite_estimate.hpp): priced by the mesh's triangles and the query
// set's size from what has run, one build per structure.
#include <gtest/gtest.h>

#include <string>

#include "harness/run/calibration.hpp"
#include "harness/run/run_job.hpp"
#include "harness/run/suite_estimate.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {

/// A PLY header of `faces` faces (the estimate reads no further).
void write_ply_header(const std::string& path, long faces) {
  write_file_bytes(path, "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                         "property float z\nelement face " + std::to_string(faces) +
                         "\nproperty list uchar int vertex_indices\nend_header\n");
}

SuiteConfig suite_on(TmpDir& d, const std::string& mesh, long n) {
  write_file_bytes(d.file(mesh + ".yml"), "name: e\ntruth: false\nrepeat: 3\nmatrices:\n  - meshes: [" + mesh +
                                              ".ply]\n    queries: [{kind: random, n: " + std::to_string(n) +
                                              ", seed: 1}, {kind: haptic, n: " + std::to_string(n) +
                                              ", seed: 1}]\n    query: [inside, distance]\n    methods: [ebp_octree]\n");
  return load_suite(d.file(mesh + ".yml"));
}

/// Every job of `cfg` in each of its rounds.
SuitePrice price_of(const SuiteEstimator& e, const SuiteConfig& cfg, bool shared, const std::string& data) {
  const std::vector<std::vector<bool>> every_round(std::size_t(cfg.rounds), std::vector<bool>(cfg.jobs.size(), true));
  return e.price(cfg, cfg.jobs, every_round, group_by_structure(cfg.jobs), shared, data);
}

/// A finished ebp_octree job on `triangles` triangles: 1 s of build, 1e5 queries/s, beside a
/// calibration kernel of `kernel_seconds` (none when 0).
void write_observation(const std::string& runs, double triangles, double kernel_seconds = 0) {
  JobSpec spec;
  nlohmann::json r = make_result(spec, status::ok, "");
  r["job"]["method"] = "ebp_octree";
  r["job"]["params_key"] = "";
  r["job"]["query"] = "inside";
  r["job"]["repetitions"] = 3;
  r["job"]["mesh"]["triangles"] = triangles;
  r["job"]["queries"]["kind"] = "random";
  r["queries"] = {{"n", 1000}, {"throughput_qps", {{"median", 1e5}}}};
  r["build"] = {{"seconds", 1.0}};
  r["elapsed_seconds"] = 2.0;
  if (kernel_seconds > 0) r["calibration"] = {{"kernel", kCalibrationKernel}, {"median_seconds", kernel_seconds}};
  std::filesystem::create_directories(runs);
  write_json_atomic(runs + "/obs.json", r);
}

}  // namespace

TEST(SuiteEstimate, TheTriangleCountComesFromTheHeaderTheManifestOrThePreset) {
  TmpDir d;
  write_ply_header(d.file("m.ply"), 123456);
  EXPECT_EQ(mesh_triangles(d.file("m.ply")), 123456);
  // Not made yet: the manifest beside it, else its preset's declared size.
  write_file_bytes(d.file("manifest.json"), R"({"meshes": [{"file": "later.ply", "triangles": 777}]})");
  EXPECT_EQ(mesh_triangles(d.file("later.ply")), 777);
  EXPECT_EQ(mesh_triangles(d.file("paper/bunny_closed_32m.ply")), 32000000);
  EXPECT_EQ(mesh_triangles(d.file("nowhere/unknown.ply")), 0);
}

TEST(SuiteEstimate, ATenTimesBiggerMeshOrQuerySetIsPricedHigher) {
  TmpDir d;
  write_ply_header(d.file("small.ply"), 100000);
  write_ply_header(d.file("big.ply"), 1000000);
  for (const bool observed : {false, true}) {
    SCOPED_TRACE(observed ? "from an observation" : "from the defaults");
    if (observed) write_observation(d.file("seen/runs"), 50000);
    const SuiteEstimator e(observed ? std::vector<std::string>{d.file("seen")} : std::vector<std::string>{});
    EXPECT_EQ(e.observations(), observed ? 1u : 0u);
    const SuitePrice small = price_of(e, suite_on(d, "small", 1000), true, d.file("data"));
    const SuitePrice big = price_of(e, suite_on(d, "big", 1000), true, d.file("data"));
    const SuitePrice more = price_of(e, suite_on(d, "small", 10000), true, d.file("data"));
    EXPECT_GT(big.total(), small.total() + 0.5);
    // From an observed build (1 s at 50k triangles), ten times the triangles is over ten times the build.
    if (observed) {
      EXPECT_GT(big.total(), 3 * small.total());
    }
    EXPECT_GT(more.total(), small.total());
    EXPECT_EQ(small.jobs, 4u);
    // The observation is of inside queries: the distance jobs are priced at the median rates.
    EXPECT_EQ(small.guessed, observed ? 2u : 4u);
  }
}

TEST(SuiteEstimate, AStructureSharedByItsJobsIsBuiltOnce) {
  TmpDir d;
  write_ply_header(d.file("big.ply"), 5000000);
  write_observation(d.file("seen/runs"), 5000000);
  const SuiteEstimator e({d.file("seen")});
  const SuiteConfig cfg = suite_on(d, "big", 1000);
  const SuitePrice shared = price_of(e, cfg, true, d.file("data"));
  const SuitePrice alone = price_of(e, cfg, false, d.file("data"));
  EXPECT_EQ(shared.builds, 1u);
  EXPECT_EQ(alone.builds, 4u);
  // Three builds of 1 s (and three mesh loads) fewer.
  EXPECT_GT(alone.total() - shared.total(), 3.0);
}

// Each round runs every job again on a structure built again; the query sets are made once.
TEST(SuiteEstimate, EachRoundIsPricedAgainButTheDataOnce) {
  TmpDir d;
  write_ply_header(d.file("big.ply"), 5000000);
  write_observation(d.file("seen/runs"), 5000000);
  const SuiteEstimator e({d.file("seen")});
  SuiteConfig cfg = suite_on(d, "big", 1000);
  const SuitePrice once = price_of(e, cfg, true, d.file("data"));
  cfg.rounds = 3;
  const SuitePrice thrice = price_of(e, cfg, true, d.file("data"));
  EXPECT_EQ(thrice.jobs, once.jobs);
  EXPECT_EQ(thrice.runs, 3 * once.runs);
  EXPECT_EQ(thrice.builds, 3 * once.builds);
  EXPECT_GT(thrice.data_seconds, 0.0);
  EXPECT_DOUBLE_EQ(thrice.data_seconds, once.data_seconds);
  EXPECT_NEAR(thrice.total() - thrice.data_seconds, 3 * (once.total() - once.data_seconds), 1e-9 * once.total());
  for (std::size_t i = 0; i < cfg.jobs.size(); ++i) {
    EXPECT_EQ(thrice.job_runs[i], 3);
    EXPECT_NEAR(thrice.run_seconds(i), once.run_seconds(i), 1e-12);
  }
  EXPECT_NE(thrice.describe().find("4 job(s) to run in 3 rounds (12 run(s)), 3 build(s)"), std::string::npos)
      << thrice.describe();
  EXPECT_EQ(once.describe().find("round"), std::string::npos) << once.describe();
  // --resume after round 1: the rounds left alone are priced.
  std::vector<std::vector<bool>> left(3, std::vector<bool>(cfg.jobs.size(), true));
  left[0].assign(cfg.jobs.size(), false);
  const SuitePrice two_left = e.price(cfg, cfg.jobs, left, group_by_structure(cfg.jobs), true, d.file("data"));
  EXPECT_EQ(two_left.runs, 2 * once.runs);
  EXPECT_NEAR(two_left.total() - two_left.data_seconds, 2 * (once.total() - once.data_seconds), 1e-9 * once.total());
}

TEST(SuiteEstimate, AResultMadeOnASlowerMachineIsScaledByTheCalibrationKernel) {
  TmpDir d;
  write_ply_header(d.file("big.ply"), 5000000);
  write_observation(d.file("seen/runs"), 5000000, 0.1);
  const SuiteConfig cfg = suite_on(d, "big", 100000);
  const SuitePrice as_measured = price_of(SuiteEstimator({d.file("seen")}), cfg, true, d.file("data"));
  const SuitePrice same = price_of(SuiteEstimator({d.file("seen")}, 0.1), cfg, true, d.file("data"));
  const SuitePrice faster = price_of(SuiteEstimator({d.file("seen")}, 0.02), cfg, true, d.file("data"));
  EXPECT_DOUBLE_EQ(same.total(), as_measured.total());
  EXPECT_EQ(same.rescaled, 0u);
  EXPECT_EQ(faster.rescaled, 1u);
  // Inside jobs: one build of 1 s and 5 passes of 1e5 queries at 1e5/s, each five times faster
  // here; the distance jobs are priced at the (scaled) median rates too.
  EXPECT_LT(faster.total(), 0.4 * as_measured.total());
  EXPECT_GT(faster.total(), 0.1 * as_measured.total());
}

TEST(SuiteEstimate, TheTimeLeftFollowsHowTheFinishedJobsCompared) {
  EXPECT_DOUBLE_EQ(time_left(100, 0, 0), 100);
  EXPECT_DOUBLE_EQ(time_left(100, 10, 20), 200);  // twice as slow as priced
  EXPECT_DOUBLE_EQ(time_left(100, 10, 5), 50);
}

// A probe path (haptic, contact) builds a triangle grid over the whole mesh: on 100M triangles it
// is priced tens of seconds above a random set of the same size, which needs only the mesh's box.
TEST(SuiteEstimate, AProbePathOnALargeMeshIsPricedForItsGrid) {
  TmpDir d;
  write_ply_header(d.file("large.ply"), 100000000);
  const SuiteEstimator e({});
  auto data_seconds_of = [&](const std::string& kind) {
    write_file_bytes(d.file(kind + ".yml"), "name: e\ntruth: false\nmatrices:\n  - meshes: [large.ply]\n    queries: [{kind: " +
                                                kind + ", n: 1000, seed: 1}]\n    query: [distance]\n    methods: [ebp_octree]\n");
    const SuiteConfig cfg = load_suite(d.file(kind + ".yml"));
    return price_of(e, cfg, true, d.file("data")).data_seconds;
  };
  EXPECT_GT(data_seconds_of("haptic"), data_seconds_of("random") + 20);
  EXPECT_GT(data_seconds_of("contact"), data_seconds_of("random") + 20);
}
