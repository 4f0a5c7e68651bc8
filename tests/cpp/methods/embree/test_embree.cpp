// embree against brute_force on every mesh in ../shared/meshes and a procedural sphere, for
// each build quality, robust mode, vote and coherence variant, plus the degenerate cases (one triangle, a point on a vertex, a
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

#define SKIP_WITHOUT_EMBREE() \
  if (!Registry::global().find("embree")) GTEST_SKIP() << "embree method not built"

const char* const kVariants[] = {"embree", "embree:quality=low", "embree:quality=high",
                                 "embree:robust=false", "embree:rays=3", "embree:rays=5",
                                 "embree:coherent=true", "embree:quality=high,robust=false,coherent=true,rays=3"};

class EmbreeSharedMesh : public ::testing::TestWithParam<SharedMesh> {};

}  // namespace

TEST(Embree, ListedWithParameters) {
  SKIP_WITHOUT_EMBREE();
  const MethodInfo* info = Registry::global().find("embree");
  EXPECT_TRUE(info->caps.inside && info->caps.distance && info->caps.closest_triangle && info->caps.coherence);
  std::vector<std::string> names;
  for (const auto& p : info->params) names.push_back(p.name);
  for (const char* want : {"quality", "robust", "rays", "coherent", "threads"})
    EXPECT_NE(std::find(names.begin(), names.end(), want), names.end()) << want;
}

TEST(Embree, SphereAgainstBruteForce) {
  SKIP_WITHOUT_EMBREE();
  const Mesh s = icosphere(3);
  const auto q = sample_queries(s, 150, 150, 7);
  for (const char* v : kVariants) expect_matches_brute_force(v, s, true, q);
}

TEST_P(EmbreeSharedMesh, AgainstBruteForce) {
  SKIP_WITHOUT_EMBREE();
  const SharedMesh& sm = GetParam();
  const Mesh mesh = load_shared_mesh(sm.file);
  const auto q = sample_queries(mesh, sm.n_random, sm.n_near, 11);
  expect_matches_brute_force("embree", mesh, sm.closed, q);
  expect_matches_brute_force("embree:quality=high,rays=3", mesh, sm.closed, q);
}

TEST_P(EmbreeSharedMesh, CoherentPathSameAnswers) {
  SKIP_WITHOUT_EMBREE();
  const Mesh mesh = load_shared_mesh(GetParam().file);
  const auto path = sample_path(mesh, 300, 3);
  expect_coherent_replay_matches("embree", "embree:coherent=true", mesh, path);
  expect_coherent_replay_matches("embree:quality=high", "embree:coherent=true,quality=high", mesh, path);
}

INSTANTIATE_TEST_SUITE_P(SharedMeshes, EmbreeSharedMesh, ::testing::ValuesIn(float32_method_meshes()),
                         SharedMeshName());

TEST(Embree, OneTriangleQueryOnVertexAndFarAway) {
  SKIP_WITHOUT_EMBREE();
  for (const char* v : kVariants) expect_one_triangle_answers(v);
}

TEST(Embree, QueryOnAVertexOfAClosedMesh) {
  SKIP_WITHOUT_EMBREE();
  for (const char* v : kVariants) expect_cube_surface_answers(v);
}

TEST(Embree, DuplicateAndZeroAreaTriangles) {
  SKIP_WITHOUT_EMBREE();
  for (const char* v : kVariants) expect_degenerate_triangle_answers(v);
}

TEST(Embree, AllDegenerateMeshDoesNotCrash) {
  SKIP_WITHOUT_EMBREE();
  for (const char* v : kVariants) expect_all_degenerate_answers(v);
}

TEST(Embree, CountersAndBytes) {
  SKIP_WITHOUT_EMBREE();
  const Mesh s = icosphere(3);
  auto d = build_method("embree", s, QueryType::distance);
  EXPECT_GT(d->structure_bytes(), s.triangles.size() * 12 + s.vertices.size() * 12);  // + the BVH
  const auto queries = sample_queries(s, 20, 0, 1);
  const auto first = count_distance_pass(*d, queries);
  auto c = counter_values(first);
  EXPECT_GT(c["triangles_tested"], 0u);
  EXPECT_EQ(c["point_queries"], 20u);
  EXPECT_LT(c["triangles_tested"], 20u * s.triangles.size());  // the tree prunes
  // Deterministic: the same pass counts the same work.
  const auto second = count_distance_pass(*d, queries);
  for (std::size_t i = 0; i < first.size(); ++i) EXPECT_EQ(first[i].value, second[i].value) << first[i].name;
}

TEST(Embree, VotesShootOneRayEachAtLeast) {
  SKIP_WITHOUT_EMBREE();
  const Mesh s = icosphere(2);
  for (int rays : {1, 3, 5}) {
    auto in = build_method("embree:rays=" + std::to_string(rays), s, QueryType::inside);
    in->reset_counters();
    EXPECT_TRUE(in->inside({0.1, 0.2, 0.3}));
    EXPECT_FALSE(in->inside({0.9, 0.9, 0.9}));  // in the box, outside the sphere: rays needed
    auto c = counter_values(*in);
    EXPECT_GE(c["rays_shot"], 2u * unsigned(rays));
    EXPECT_EQ(c["undecided"], 0u);
  }
}
