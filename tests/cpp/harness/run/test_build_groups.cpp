// Which suite jobs share one structure (run/build_groups.hpp): one mesh, one method with its
// options, one thread count; narrowed by the method's StructureSharing.
#include <gtest/gtest.h>

#include <string>

#include "harness/run/build_groups.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {

SuiteConfig suite_of(TmpDir& d, const std::string& methods, const std::string& extra = "") {
  write_file_bytes(d.file("s.yml"), "name: g\ntruth: false\nmatrices:\n  - meshes: [a.ply, b.ply]\n"
                                    "    queries: [{kind: random, n: 10, seed: 1}, {kind: haptic, n: 10, seed: 1}]\n"
                                    "    query: [inside, distance]\n    methods: " + methods + "\n" + extra);
  return load_suite(d.file("s.yml"));
}

/// The ids of the jobs in group g.
std::vector<std::string> ids(const SuiteConfig& cfg, const BuildGroup& g) {
  std::vector<std::string> out;
  for (std::size_t i : g.jobs) out.push_back(cfg.jobs[i].id);
  return out;
}

}  // namespace

TEST(BuildGroups, OneStructurePerMeshAndMethodServesEveryQuerySetAndType) {
  TmpDir d;
  const SuiteConfig cfg = suite_of(d, "[brute_force, \"brute_force:winding_threshold=0.4\"]");
  ASSERT_EQ(cfg.jobs.size(), 16u);
  const std::vector<BuildGroup> groups = group_by_structure(cfg.jobs);
  ASSERT_EQ(groups.size(), 4u);  // 2 meshes x 2 configurations
  for (const BuildGroup& g : groups) {
    SCOPED_TRACE(g.id);
    ASSERT_EQ(g.jobs.size(), 4u);  // 2 query sets x inside, distance
    for (std::size_t i : g.jobs) {
      EXPECT_EQ(cfg.jobs[i].mesh.path, cfg.jobs[g.jobs[0]].mesh.path);
      EXPECT_EQ(cfg.jobs[i].method.text, cfg.jobs[g.jobs[0]].method.text);
    }
    for (std::size_t k = 1; k < g.jobs.size(); ++k) EXPECT_LT(g.jobs[k - 1], g.jobs[k]);  // suite order
  }
  EXPECT_EQ(groups[0].id, "a__brute_force");
  EXPECT_EQ(groups[1].id, "a__brute_force-winding_threshold=0.4");
}

TEST(BuildGroups, AMethodNarrowsWhatItsStructureServes) {
  TmpDir d;
  // cgal_aabb builds its KD-tree for distance jobs only: one structure per query type, unless
  // the tree is off. openvdb sizes its band from the job's points: each job alone.
  const SuiteConfig cfg = suite_of(d, "[cgal_aabb, \"cgal_aabb:kd_tree=false\", openvdb]");
  const std::vector<BuildGroup> groups = group_by_structure(cfg.jobs);
  std::size_t cgal_type = 0, cgal_all = 0, vdb = 0;
  for (const BuildGroup& g : groups) {
    const JobPlan& first = cfg.jobs[g.jobs[0]];
    if (first.method.text == "cgal_aabb") {
      ++cgal_type;
      ASSERT_EQ(g.jobs.size(), 2u) << g.id;  // two query sets, one type
      EXPECT_EQ(cfg.jobs[g.jobs[1]].query, first.query);
    } else if (first.method.text == "cgal_aabb:kd_tree=false") {
      ++cgal_all;
      EXPECT_EQ(g.jobs.size(), 4u) << g.id;
    } else {
      ++vdb;
      ASSERT_EQ(g.jobs.size(), 1u);
      EXPECT_EQ(g.id, first.id) << "a job alone is its own group, named by its id";
    }
  }
  EXPECT_EQ(cgal_type, 4u);  // 2 meshes x 2 types
  EXPECT_EQ(cgal_all, 2u);
  EXPECT_EQ(vdb, 8u);
}

TEST(BuildGroups, ThreadsAreAStructureOfTheirOwn) {
  TmpDir d;
  write_file_bytes(d.file("s.yml"), "name: g\ntruth: false\nmatrices:\n  - meshes: [a.ply]\n"
                                    "    queries: [{kind: random, n: 10, seed: 1}]\n"
                                    "    query: [inside, distance]\n    threads: [1, 2]\n    methods: [ebp_octree]\n");
  const SuiteConfig cfg = load_suite(d.file("s.yml"));
  const std::vector<BuildGroup> groups = group_by_structure(cfg.jobs);
  ASSERT_EQ(groups.size(), 2u);
  EXPECT_EQ(groups[0].id, "a__ebp_octree");
  EXPECT_EQ(groups[1].id, "a__ebp_octree__t2");
  EXPECT_EQ(ids(cfg, groups[1]).size(), 2u);
}

TEST(BuildGroups, QueryOptionsShareTheStructureWhereTheMethodTakesThemAfterItsBuild) {
  TmpDir d;
  // coherent is a query option of the EBP-Octree and Embree, which take it after their build;
  // leaf_factor is a build option. brute_force's winding_threshold is a query option too, but
  // brute_force does not take options after its build: each configuration is its own structure.
  const SuiteConfig cfg = suite_of(d, "[ebp_octree, \"ebp_octree:coherent=true\", \"ebp_octree:leaf_factor=8\", "
                                      "\"embree:coherent=true\", \"embree:rays=3\", "
                                      "\"brute_force:winding_threshold=0.4\", brute_force]");
  const std::vector<BuildGroup> groups = group_by_structure(cfg.jobs);
  std::vector<std::string> group_ids;
  for (const BuildGroup& g : groups) group_ids.push_back(g.id);
  EXPECT_EQ(group_ids, (std::vector<std::string>{"a__ebp_octree", "a__ebp_octree-leaf_factor=8", "a__embree",
                                                 "a__brute_force-winding_threshold=0.4", "a__brute_force",
                                                 "b__ebp_octree", "b__ebp_octree-leaf_factor=8", "b__embree",
                                                 "b__brute_force-winding_threshold=0.4", "b__brute_force"}));
  EXPECT_EQ(groups[0].jobs.size(), 8u);  // plain and coherent x 2 query sets x 2 types
  EXPECT_EQ(groups[2].jobs.size(), 8u);
  EXPECT_EQ(groups[1].jobs.size(), 4u);
  EXPECT_EQ(groups[3].jobs.size(), 4u);
}
