// The parameter variants of the float32 methods (cgal_aabb, embree) against brute_force: what the
// method-conformance suite (test_conformance.cpp) does not run, since it builds each method with
// its defaults and with coherent=true only. One table says, for each method, the parameters it
// declares and the variants worth checking; one set of checks runs them all.
//
// Each variant: on a procedural sphere and (one variant per method) on every mesh in
// ../shared/meshes, against brute_force built on the same float32-rounded mesh, with the
// tolerances of expect_matches_brute_force (test_support.hpp); the degenerate cases (one
// triangle, points on a vertex, an edge and a face of a cube, duplicate and zero-area triangles,
// an all-degenerate mesh); a coherent variant of a non-default build replayed along an ordered
// path with the answers of the same build without coherence (expect_coherent_replay_matches).
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <tuple>
#include <vector>

#include "harness/core/mesh.hpp"
#include "harness/core/registry.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {

/// One method's parameter variants.
struct MethodVariants {
  const char* method;
  std::vector<const char*> params;    ///< parameters it must declare
  std::vector<const char*> variants;  ///< non-default builds, each checked on the sphere and the degenerate cases
  const char* shared_mesh_variant;    ///< the one also checked on every shared mesh
  const char* plain;                  ///< a non-default build ...
  const char* coherent;               ///< ... and the same with coherent=true
};

void PrintTo(const MethodVariants& m, std::ostream* os) { *os << m.method; }

const std::vector<MethodVariants>& float32_method_variants() {
  static const std::vector<MethodVariants> table = {
      {"cgal_aabb",
       {"kernel", "kd_tree", "coherent"},
       {"cgal_aabb:kernel=simple_cartesian", "cgal_aabb:kd_tree=false",
        "cgal_aabb:kernel=simple_cartesian,coherent=true,kd_tree=false"},
       "cgal_aabb:kernel=simple_cartesian,kd_tree=false",
       "cgal_aabb:kd_tree=false",
       "cgal_aabb:coherent=true,kd_tree=false"},
      {"embree",
       {"quality", "robust", "rays", "coherent"},
       {"embree:quality=low", "embree:quality=high", "embree:robust=false", "embree:rays=3", "embree:rays=5",
        "embree:quality=high,robust=false,coherent=true,rays=3"},
       "embree:quality=high,rays=3",
       "embree:quality=high",
       "embree:coherent=true,quality=high"},
  };
  return table;
}

#define SKIP_UNLESS_BUILT(m) \
  if (!Registry::global().find((m).method)) GTEST_SKIP() << (m).method << " method not built"

class ParameterVariants : public ::testing::TestWithParam<MethodVariants> {};

class ParameterVariantsOnSharedMesh : public ::testing::TestWithParam<std::tuple<MethodVariants, SharedMesh>> {};

}  // namespace

TEST_P(ParameterVariants, ListedWithParameters) {
  const MethodVariants& m = GetParam();
  SKIP_UNLESS_BUILT(m);
  const MethodInfo* info = Registry::global().find(m.method);
  EXPECT_TRUE(info->caps.inside && info->caps.distance && info->caps.closest_triangle && info->caps.coherence);
  std::vector<std::string> names;
  for (const auto& p : info->params) names.push_back(p.name);
  for (const char* want : m.params) EXPECT_NE(std::find(names.begin(), names.end(), want), names.end()) << want;
}

TEST_P(ParameterVariants, SphereAgainstBruteForce) {
  const MethodVariants& m = GetParam();
  SKIP_UNLESS_BUILT(m);
  const Mesh s = icosphere(3);
  const auto q = sample_queries(s, 150, 150, 7);
  for (const char* v : m.variants) expect_matches_brute_force(v, s, true, q);
}

// One triangle (points on a vertex, an edge, the face, far away); a cube queried on a vertex, an
// edge and a face; duplicate and zero-area triangles; a mesh of zero-area triangles only.
TEST_P(ParameterVariants, HandMadeCases) {
  const MethodVariants& m = GetParam();
  SKIP_UNLESS_BUILT(m);
  for (const char* v : m.variants) {
    SCOPED_TRACE(v);
    expect_one_triangle_answers(v);
    expect_cube_surface_answers(v);
    expect_degenerate_triangle_answers(v);
    expect_all_degenerate_answers(v);
  }
}

INSTANTIATE_TEST_SUITE_P(Float32Methods, ParameterVariants, ::testing::ValuesIn(float32_method_variants()),
                         [](const auto& info) { return std::string(info.param.method); });

TEST_P(ParameterVariantsOnSharedMesh, AgainstBruteForce) {
  const MethodVariants& m = std::get<0>(GetParam());
  SKIP_UNLESS_BUILT(m);
  const SharedMesh& sm = std::get<1>(GetParam());
  const Mesh mesh = load_shared_mesh(sm.file);
  const auto q = sample_queries(mesh, sm.n_random, sm.n_near, 11);
  expect_matches_brute_force(m.shared_mesh_variant, mesh, sm.closed, q);
}

TEST_P(ParameterVariantsOnSharedMesh, CoherentPathSameAnswers) {
  const MethodVariants& m = std::get<0>(GetParam());
  SKIP_UNLESS_BUILT(m);
  const Mesh mesh = load_shared_mesh(std::get<1>(GetParam()).file);
  expect_coherent_replay_matches(m.plain, m.coherent, mesh, sample_path(mesh, 300, 3));
}

INSTANTIATE_TEST_SUITE_P(Float32Methods, ParameterVariantsOnSharedMesh,
                         ::testing::Combine(::testing::ValuesIn(float32_method_variants()),
                                            ::testing::ValuesIn(float32_method_meshes())),
                         [](const auto& info) {
                           return std::string(std::get<0>(info.param).method) + "__" +
                                  mesh_stem(std::get<1>(info.param).file, "_");
                         });
