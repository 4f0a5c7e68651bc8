// brute_force on hand-computed cases: a point on a vertex, an edge, a face; inside and outside a
// cube; a point near an open surface; the degenerate inputs.
#include <gtest/gtest.h>

#include <cmath>

#include "harness/core/mesh.hpp"
#include "harness/core/registry.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

namespace {

/// brute_force built with a default BuildContext (query type inside).
std::unique_ptr<Method> built(const Mesh& mesh) { return build_method("brute_force", mesh, QueryType::inside); }

}  // namespace

TEST(BruteForce, InsideAndOutsideCube) {
  Mesh cube = unit_cube();
  auto m = built(cube);
  EXPECT_TRUE(m->inside({0.5, 0.5, 0.5}));
  EXPECT_TRUE(m->inside({0.01, 0.99, 0.5}));
  EXPECT_FALSE(m->inside({1.5, 0.5, 0.5}));
  EXPECT_FALSE(m->inside({-0.01, 0.5, 0.5}));
  EXPECT_FALSE(m->inside({10, 10, 10}));
}

TEST(BruteForce, CubeDistanceSignAndNormal) {
  auto m = built(unit_cube());
  DistanceResult d = m->distance({0.5, 0.5, 0.2});  // inside, closest face z = 0
  EXPECT_NEAR(d.distance, -0.2, 1e-15);
  EXPECT_NEAR(d.closest.z, 0.0, 1e-15);
  EXPECT_NEAR(d.normal.z, -1.0, 1e-15);  // outward normal of the bottom face
  EXPECT_TRUE(d.triangle == 0 || d.triangle == 1);
  d = m->distance({2, 0.5, 0.5});  // outside, closest face x = 1
  EXPECT_NEAR(d.distance, 1.0, 1e-15);
  EXPECT_NEAR(d.normal.x, 1.0, 1e-15);
  d = m->distance({2, 2, 2});  // closest feature: the vertex (1,1,1)
  EXPECT_NEAR(d.distance, std::sqrt(3.0), 1e-14);
  EXPECT_EQ(d.closest, Vec3d(1, 1, 1));
}

TEST(BruteForce, PointOnVertexEdgeFace) {
  auto m = built(one_triangle());
  for (Vec3d p : {Vec3d{0, 0, 0}, Vec3d{1, 0, 0}, Vec3d{0.5, 0, 0}, Vec3d{0.5, 0.5, 0}, Vec3d{0.2, 0.2, 0}}) {
    DistanceResult d = m->distance(p);
    // Exact on vertices and edges; a face-interior point goes through barycentric coordinates,
    // so it is exact up to rounding.
    EXPECT_NEAR(std::abs(d.distance), 0.0, 1e-15) << p.x << "," << p.y;
    EXPECT_NEAR(norm(d.closest - p), 0.0, 1e-15);
    EXPECT_EQ(d.triangle, 0);
  }
  // Off the plane: edge and vertex regions.
  DistanceResult d = m->distance({0.5, -1, 0});
  EXPECT_NEAR(d.distance, 1.0, 1e-15);
  EXPECT_EQ(d.closest, Vec3d(0.5, 0, 0));
  d = m->distance({-1, -1, 1});
  EXPECT_NEAR(d.distance, std::sqrt(3.0), 1e-15);
  EXPECT_EQ(d.closest, Vec3d(0, 0, 0));
  d = m->distance({0.25, 0.25, 3});
  EXPECT_NEAR(d.distance, 3.0, 1e-15);
  EXPECT_NEAR(d.normal.z, 1.0, 1e-15);
}

TEST(BruteForce, OpenSurfaceWindingIsFractional) {
  // A cube without its top. Inside, w = 1 - (solid angle of the opening) / 4 pi: close to 1 near
  // the bottom, just above 1/2 right under the opening (which subtends almost a half-space);
  // above the opening w = (solid angle of the walls seen from outside) / 4 pi < 1/2.
  Mesh cup = open_cup();
  auto m = built(cup);
  EXPECT_TRUE(m->inside({0.5, 0.5, 0.05}));
  EXPECT_TRUE(m->inside({0.5, 0.5, 0.99}));
  EXPECT_FALSE(m->inside({0.5, 0.5, 1.01}));
  EXPECT_FALSE(m->inside({0.5, 0.5, 1.5}));
  // A threshold above the winding right under the opening flips that answer, not the others.
  auto strict = Registry::global().create("brute_force:winding_threshold=0.9");
  strict->build(cup, BuildContext{});
  EXPECT_TRUE(strict->inside({0.5, 0.5, 0.05}));
  EXPECT_FALSE(strict->inside({0.5, 0.5, 0.99}));
}

TEST(BruteForce, DegenerateTrianglesDoNotBreakIt) {
  Mesh cube = unit_cube();
  cube.vertices.push_back({0.5, 0.5, 0.5});
  cube.triangles.push_back({8, 8, 8});  // collapsed to a point
  cube.triangles.push_back({0, 1, 1});  // zero-area
  cube.triangles.push_back(cube.triangles[0]);  // duplicate
  auto m = built(cube);
  DistanceResult d = m->distance({0.5, 0.5, 0.5});
  EXPECT_EQ(d.distance, 0.0);  // on the collapsed triangle
  EXPECT_EQ(d.triangle, 12);
  EXPECT_TRUE(std::isfinite(d.normal.x));
}

TEST(BruteForce, CountersAreExact) {
  Mesh cube = unit_cube();
  auto m = built(cube);
  m->reset_counters();
  m->inside({0.5, 0.5, 0.5});
  m->distance({0.5, 0.5, 0.5});  // 12 for the distance, 12 for its sign
  auto c = m->counters();
  ASSERT_EQ(c.size(), 1u);
  EXPECT_EQ(c[0].name, "triangles_tested");
  EXPECT_EQ(c[0].value, 36u);
}
