// mesh_stats (what `bvhbench mesh-info` reports about a mesh): each count on a mesh made to have
// exactly that many of it, and the two meanings of closed.
#include <gtest/gtest.h>

#include "harness/core/mesh.hpp"
#include "harness/core/mesh_stats.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

TEST(MeshStats, CubeIsClosed) {
  const MeshStats s = mesh_stats(unit_cube());
  EXPECT_EQ(s.edges, 18u);
  EXPECT_EQ(s.boundary_edges, 0u);
  EXPECT_EQ(s.nonmanifold_edges, 0u);
  EXPECT_EQ(s.misoriented_edges, 0u);
  EXPECT_TRUE(s.closed());
  EXPECT_TRUE(s.balanced());
  EXPECT_EQ(s.degenerate_triangles, 0u);
  EXPECT_EQ(s.unreferenced_vertices, 0u);
  EXPECT_EQ(s.bounds.lo, Vec3d(0, 0, 0));
  EXPECT_EQ(s.bounds.hi, Vec3d(1, 1, 1));
}

TEST(MeshStats, OpenCupHasFourBoundaryEdges) {
  const MeshStats s = mesh_stats(open_cup());
  EXPECT_EQ(s.boundary_edges, 4u);
  EXPECT_FALSE(s.closed());
  EXPECT_FALSE(s.balanced());
}

TEST(MeshStats, FlippedTriangleIsMisoriented) {
  Mesh m = unit_cube();
  std::swap(m.triangles[0][1], m.triangles[0][2]);
  const MeshStats s = mesh_stats(m);
  EXPECT_EQ(s.misoriented_edges, 3u);
  EXPECT_EQ(s.boundary_edges, 0u);
  EXPECT_FALSE(s.closed());
  EXPECT_FALSE(s.balanced());
}

TEST(MeshStats, TwoCubesOnOneEdgeAreBalancedNotClosed) {
  Mesh m = unit_cube();
  const Mesh b = unit_cube();
  // The second cube shifted by (1, 1, 0) shares the vertical edge x = y = 1 (vertices 2 and 6).
  std::vector<std::uint32_t> id(8);
  for (std::uint32_t i = 0; i < 8; ++i) {
    const Vec3d p = b.vertices[i] + Vec3d(1, 1, 0);
    id[i] = p == Vec3d(1, 1, 0) ? 2 : p == Vec3d(1, 1, 1) ? 6 : std::uint32_t(m.vertices.size());
    if (id[i] >= 8) m.vertices.push_back(p);
  }
  for (const auto& t : b.triangles) m.triangles.push_back({id[t[0]], id[t[1]], id[t[2]]});
  const MeshStats s = mesh_stats(m);
  EXPECT_EQ(s.nonmanifold_edges, 1u);
  EXPECT_FALSE(s.closed());
  EXPECT_TRUE(s.balanced()) << "each cube uses the shared edge once in each direction";
}

TEST(MeshStats, DuplicateTriangleMakesNonManifoldEdges) {
  Mesh m = unit_cube();
  m.triangles.push_back(m.triangles[3]);
  const MeshStats s = mesh_stats(m);
  EXPECT_EQ(s.nonmanifold_edges, 3u);
  EXPECT_FALSE(s.balanced());
}

TEST(MeshStats, DegenerateTrianglesAndUnusedVertices) {
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.5, 0.5, 0}, {1, 0, 0}, {7, 7, 7}};
  m.triangles = {{0, 1, 2},   // a proper triangle
                 {1, 3, 2},   // three distinct collinear corners: 0.5 0.5 is on x + y = 1, exactly
                 {0, 1, 4},   // two corners at one position, distinct indices
                 {0, 0, 2}};  // a repeated index
  const MeshStats s = mesh_stats(m);
  EXPECT_EQ(s.degenerate_triangles, 3u);
  EXPECT_EQ(s.unreferenced_vertices, 1u);
  EXPECT_EQ(s.bounds.hi, Vec3d(7, 7, 7)) << "unused vertices count in the bounds";
  // A corner off the line by one ulp is not degenerate.
  m.vertices[3].x = std::nextafter(0.5, 1.0);
  EXPECT_EQ(mesh_stats(m).degenerate_triangles, 2u);
}

TEST(MeshStats, ClosedSharedMeshes) {
  for (const char* name : {"cow.obj", "fandisk.obj", "homer.obj", "rocker-arm.obj"}) {
    EXPECT_TRUE(mesh_stats(load_shared_mesh(name)).closed()) << name;
  }
  EXPECT_FALSE(mesh_stats(load_shared_mesh("stanford-bunny.obj")).closed());
}
