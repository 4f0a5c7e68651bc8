// cgal_aabb against brute_force on every mesh in ../shared/meshes and a procedural sphere, for
// each kernel and hint variant, plus the degenerate cases (one triangle, a point on a vertex, a
// point far outside, duplicate and zero-area triangles, an all-degenerate mesh).
//
// The method keeps float32 geometry (the contract), so the reference is brute_force built on the
// same float32-rounded mesh; the tolerances are those of expect_matches_brute_force and
// expect_coherent_replay_matches (test_support.hpp). Coherent variants are replayed along an
// ordered path and must give the same answers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "harness/core/mesh.hpp"
#include "harness/core/registry.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {

#define SKIP_WITHOUT_CGAL() \
  if (!Registry::global().find("cgal_aabb")) GTEST_SKIP() << "cgal_aabb method not built"

const char* const kVariants[] = {"cgal_aabb", "cgal_aabb:kernel=simple_cartesian",
                                 "cgal_aabb:kd_tree=false", "cgal_aabb:coherent=true",
                                 "cgal_aabb:kernel=simple_cartesian,coherent=true,kd_tree=false"};

class CgalAabbSharedMesh : public ::testing::TestWithParam<SharedMesh> {};

}  // namespace

TEST(CgalAabb, ListedWithParameters) {
  SKIP_WITHOUT_CGAL();
  const MethodInfo* info = Registry::global().find("cgal_aabb");
  EXPECT_TRUE(info->caps.inside && info->caps.distance && info->caps.closest_triangle && info->caps.coherence);
  std::vector<std::string> names;
  for (const auto& p : info->params) names.push_back(p.name);
  for (const char* want : {"kernel", "kd_tree", "coherent", "threads"})
    EXPECT_NE(std::find(names.begin(), names.end(), want), names.end()) << want;
}

TEST(CgalAabb, SphereAgainstBruteForce) {
  SKIP_WITHOUT_CGAL();
  const Mesh s = icosphere(3);
  const auto q = sample_queries(s, 150, 150, 7);
  for (const char* v : kVariants) expect_matches_brute_force(v, s, true, q);
}

TEST_P(CgalAabbSharedMesh, AgainstBruteForce) {
  SKIP_WITHOUT_CGAL();
  const SharedMesh& sm = GetParam();
  const Mesh mesh = load_shared_mesh(sm.file);
  const auto q = sample_queries(mesh, sm.n_random, sm.n_near, 11);
  expect_matches_brute_force("cgal_aabb", mesh, sm.closed, q);
  expect_matches_brute_force("cgal_aabb:kernel=simple_cartesian,kd_tree=false", mesh, sm.closed, q);
}

TEST_P(CgalAabbSharedMesh, CoherentPathSameAnswers) {
  SKIP_WITHOUT_CGAL();
  const Mesh mesh = load_shared_mesh(GetParam().file);
  const auto path = sample_path(mesh, 300, 3);
  expect_coherent_replay_matches("cgal_aabb", "cgal_aabb:coherent=true", mesh, path);
  expect_coherent_replay_matches("cgal_aabb:kd_tree=false", "cgal_aabb:coherent=true,kd_tree=false", mesh, path);
}

INSTANTIATE_TEST_SUITE_P(SharedMeshes, CgalAabbSharedMesh, ::testing::ValuesIn(float32_method_meshes()),
                         SharedMeshName());

TEST(CgalAabb, OneTriangleQueryOnVertexAndFarAway) {
  SKIP_WITHOUT_CGAL();
  for (const char* v : kVariants) expect_one_triangle_answers(v);
}

TEST(CgalAabb, QueryOnAVertexOfAClosedMesh) {
  SKIP_WITHOUT_CGAL();
  for (const char* v : kVariants) expect_cube_surface_answers(v);
}

TEST(CgalAabb, DuplicateAndZeroAreaTriangles) {
  SKIP_WITHOUT_CGAL();
  for (const char* v : kVariants) expect_degenerate_triangle_answers(v);
}

TEST(CgalAabb, AllDegenerateMeshDoesNotCrash) {
  SKIP_WITHOUT_CGAL();
  for (const char* v : kVariants) expect_all_degenerate_answers(v);
}

TEST(CgalAabb, CountersAndBytes) {
  SKIP_WITHOUT_CGAL();
  const Mesh s = icosphere(3);
  auto d = build_method("cgal_aabb", s, QueryType::distance);
  EXPECT_GT(d->structure_bytes(), s.triangles.size() * (12 + 4 + 64));  // geometry + ids + nodes
  const auto queries = sample_queries(s, 20, 0, 1);
  const auto first = count_distance_pass(*d, queries);
  auto c = counter_values(first);
  EXPECT_GT(c["triangles_tested"], 0u);
  EXPECT_GT(c["nodes_visited"], 0u);
  EXPECT_LT(c["triangles_tested"], 20u * s.triangles.size());  // the tree prunes
  // Deterministic: the same pass counts the same work.
  const auto second = count_distance_pass(*d, queries);
  for (std::size_t i = 0; i < first.size(); ++i) EXPECT_EQ(first[i].value, second[i].value) << first[i].name;
}
