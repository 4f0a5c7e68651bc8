// The faces whose front is outside and back inside (core/face_sides.hpp), and the distance's
// sign taken from them: on closed meshes every face it names has the brute-force winding number
// 0 just in front and 1 just behind; faces that other triangles cross, faces inside another
// part (winding 1 in front) and inverted shells are left out; an open mesh has none; and the
// signs, distances and closest triangles are those of the inside query, bit for bit, on every
// path, plain, coherent, and answered from certificates.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "harness/io/mesh_io.hpp"
#include "methods/ebp_octree/core/face_sides.hpp"
#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/core/query.hpp"
#include "methods/ebp_octree/ebp_test_support.hpp"
#include "methods/ebp_octree/store/reader.hpp"
#include "methods/ebp_octree/store/writer.hpp"
#include "support/test_support.hpp"

using namespace ebp_test;

namespace {

std::size_t count_front_outside(const Octree& t) {
  std::size_t n = 0;
  for (std::uint32_t i = 0; i < t.num_triangles; ++i) n += front_outside(t, i) ? 1 : 0;
  return n;
}

/// The unit cube moved by `off` and scaled by `s`, its vertices appended to m; `inward` flips it.
void add_cube(Mesh& m, Vec3d off, double s, bool inward) {
  const Mesh c = bvhbench::test::unit_cube();
  const std::uint32_t base = std::uint32_t(m.vertices.size());
  for (const Vec3d& v : c.vertices) m.vertices.push_back(off + v * s);
  for (auto t : c.triangles) {
    if (inward) std::swap(t[1], t[2]);
    m.triangles.push_back({base + t[0], base + t[1], base + t[2]});
  }
}

/// A point a small step in front of (+1) or behind (-1) the centroid of triangle i.
Vec3d beside_centroid(const Reference& ref, std::size_t i, double side, double step) {
  const Vec3d a = ref.v[ref.f[i][0]], b = ref.v[ref.f[i][1]], c = ref.v[ref.f[i][2]];
  const Vec3d n = bvhbench::triangle_normal(a, b, c);
  return (a + b + c) * (1.0 / 3.0) + n * (side * step);
}

/// The unit cube with every face an n x n grid of squares, each split into two triangles along
/// alternating diagonals: a closed, outward mesh whose neighbours around a vertex lie in one plane
/// and whose edges continue one another through vertices (as a mesh made by subdividing flat
/// triangles has).
Mesh grid_cube(int n) {
  Mesh m;
  std::map<std::array<int, 3>, std::uint32_t> index;
  auto vertex = [&](std::array<int, 3> g) {
    auto [it, added] = index.emplace(g, std::uint32_t(m.vertices.size()));
    if (added) m.vertices.push_back({double(g[0]) / n, double(g[1]) / n, double(g[2]) / n});
    return it->second;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;  // (u, v, axis) is right-handed
      for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) {
          auto at = [&](int di, int dj) {
            std::array<int, 3> g{};
            g[axis] = side * n;
            g[u] = i + di;
            g[v] = j + dj;
            return vertex(g);
          };
          std::array<std::uint32_t, 4> q{at(0, 0), at(1, 0), at(1, 1), at(0, 1)};  // counter-clockwise seen from +axis
          if (side == 0) std::swap(q[1], q[3]);                                    // outward: -axis
          if ((i + j) % 2 == 0) {
            m.triangles.push_back({q[0], q[1], q[2]});
            m.triangles.push_back({q[0], q[2], q[3]});
          } else {
            m.triangles.push_back({q[0], q[1], q[3]});
            m.triangles.push_back({q[1], q[2], q[3]});
          }
        }
    }
  return m;
}

/// Whether the winding numbers just in front of face i are 0 and just behind 1 at a grid of
/// points over it (a face that another triangle crosses has other values on part of it).
bool sides_hold_over_face(const Reference& ref, std::size_t i, double step) {
  const Vec3d a = ref.v[ref.f[i][0]], b = ref.v[ref.f[i][1]], c = ref.v[ref.f[i][2]];
  const Vec3d n = bvhbench::triangle_normal(a, b, c);
  for (int k = 1; k < 10; ++k)
    for (int l = 1; k + l < 10; ++l) {
      const Vec3d x = a + (b - a) * (k / 10.0) + (c - a) * (l / 10.0);
      if (std::fabs(ref.winding(x + n * step)) > 1e-6 || std::fabs(ref.winding(x - n * step) - 1.0) > 1e-6) return false;
    }
  return true;
}

}  // namespace

TEST(EbpFaceSides, EveryFaceNamedHasWindingZeroInFrontAndOneBehind) {
  std::vector<std::pair<std::string, Mesh>> meshes;
  for (const char* name : {"cow.obj", "fandisk.obj", "rocker-arm.obj"})
    meshes.push_back({name, bvhbench::load_mesh(shared_mesh(name))});
  meshes.push_back({"torus", torus(64, 32)});
  for (const auto& [name, m] : meshes) {
    SCOPED_TRACE(name);
    const Octree t = build(m);
    ASSERT_TRUE(t.closed);
    const Reference ref(m.vertices, m.triangles);
    const double step = 1e-4 * t.cell_size(t.leaf_level);
    const std::size_t named = count_front_outside(t);
    EXPECT_EQ(named, t.stats.front_outside_faces);
    // Almost every face of these clean, outward meshes (the cow's horns cross its head: those
    // faces and the ones inside it are left out).
    EXPECT_GT(named, m.triangles.size() * 9 / 10);
    std::mt19937 rng(5);
    for (std::size_t i = 0; i < m.triangles.size(); i += 1 + rng() % 7) {
      if (!front_outside(t, std::uint32_t(i))) continue;
      EXPECT_NEAR(ref.winding(beside_centroid(ref, i, +1, step)), 0.0, 1e-6) << "face " << i;
      EXPECT_NEAR(ref.winding(beside_centroid(ref, i, -1, step)), 1.0, 1e-6) << "face " << i;
    }
  }
}

TEST(EbpFaceSides, CrossedInsideAndInvertedFacesAreLeftOut) {
  {  // two cubes through each other: each crosses the other's faces; the parts inside the other
     // cube have winding 1 in front
    Mesh m;
    add_cube(m, {0, 0, 0}, 1.0, false);
    add_cube(m, {0.5, 0.25, 0.25}, 1.0, false);
    const Octree t = build(m);
    ASSERT_TRUE(t.closed);
    const Reference ref(m.vertices, m.triangles);
    for (std::uint32_t i = 0; i < m.triangles.size(); ++i) {
      if (!front_outside(t, i)) continue;
      // a named face is crossed by no other triangle: its front is outside everywhere
      for (double u : {0.1, 0.3, 0.6}) {
        const Vec3d a = ref.v[ref.f[i][0]], b = ref.v[ref.f[i][1]], c = ref.v[ref.f[i][2]];
        const Vec3d x = a + (b - a) * u + (c - a) * (0.5 * (1 - u)) + bvhbench::triangle_normal(a, b, c) * 1e-6;
        EXPECT_NEAR(ref.winding(x), 0.0, 1e-6) << "face " << i;
      }
    }
    // The faces of the first cube at x = 1 (inside the second cube, or crossed by it) and those of
    // the second at x = 0.5 are all out.
    for (std::uint32_t i = 0; i < m.triangles.size(); ++i) {
      const auto& f = m.triangles[i];
      const double x0 = m.vertices[f[0]].x, x1 = m.vertices[f[1]].x, x2 = m.vertices[f[2]].x;
      if ((i < 12 && x0 == 1 && x1 == 1 && x2 == 1) || (i >= 12 && x0 == 0.5 && x1 == 0.5 && x2 == 0.5)) {
        EXPECT_FALSE(front_outside(t, i)) << "face " << i;
      }
    }
    EXPECT_GT(count_front_outside(t), 0u);
  }
  {  // an inverted cube: its front is inside (winding -1 there, 0 behind): none
    Mesh m;
    add_cube(m, {0, 0, 0}, 1.0, true);
    const Octree t = build(m);
    ASSERT_TRUE(t.closed);
    EXPECT_EQ(count_front_outside(t), 0u);
  }
  {  // a hollow cube (the cavity's faces point into it): every face's front is outside
    Mesh m;
    add_cube(m, {0, 0, 0}, 1.0, false);
    add_cube(m, {0.25, 0.25, 0.25}, 0.5, true);
    const Octree t = build(m);
    ASSERT_TRUE(t.closed);
    EXPECT_EQ(count_front_outside(t), m.triangles.size());
  }
  {  // the same triangle twice (closed: each edge is used both ways as often): left out
    Mesh m;
    add_cube(m, {0, 0, 0}, 1.0, false);
    m.triangles.push_back(m.triangles[0]);
    m.triangles.push_back({m.triangles[0][0], m.triangles[0][2], m.triangles[0][1]});
    const Octree t = build(m);
    ASSERT_TRUE(t.closed);
    EXPECT_FALSE(front_outside(t, 0));
    EXPECT_FALSE(front_outside(t, 12));
  }
}

TEST(EbpFaceSides, FlatNeighboursAndTouchingLinesAreClean) {
  // Neighbours in one plane around a vertex, edges continuing through it; along the cube's
  // edges, a triangle of one side whose edge lies in the plane of the other side's triangle that
  // has a vertex on that edge's line beyond it (touching the line, not the triangle). No two
  // faces meet beyond what they share, so every face is named.
  const Mesh m = grid_cube(6);
  const Octree t = build(m);
  ASSERT_TRUE(t.closed);
  EXPECT_EQ(count_front_outside(t), m.triangles.size());
  const Reference ref(m.vertices, m.triangles);
  for (std::size_t i = 0; i < m.triangles.size(); i += 7) EXPECT_TRUE(sides_hold_over_face(ref, i, 1e-7)) << "face " << i;
}

TEST(EbpFaceSides, ACrossingBeyondASharedVertexLeavesBothFacesOut) {
  // Two tetrahedra with one vertex in common, the second turned about it so that its faces cut
  // through the first's: the pairs of faces through the shared vertex meet beyond it.
  Mesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.8, 0.45, -0.15}, {-0.15, 0.8, 0.45}, {0.45, -0.15, 0.8}};
  m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {0, 5, 4}, {0, 4, 6}, {0, 6, 5}, {4, 5, 6}};
  const Octree t = build(m);
  ASSERT_TRUE(t.closed);
  const Reference ref(m.vertices, m.triangles);
  std::size_t named = 0;
  for (std::uint32_t i = 0; i < m.triangles.size(); ++i) {
    if (!front_outside(t, i)) continue;
    ++named;
    EXPECT_TRUE(sides_hold_over_face(ref, i, 1e-7)) << "face " << i;
  }
  EXPECT_LT(named, m.triangles.size());  // the faces through the shared vertex cross
}

TEST(EbpFaceSides, OpenMeshHasNoneAndTheStoreRoundTripKeepsThem) {
  const Octree open = build(bvhbench::test::open_cup());
  EXPECT_FALSE(open.closed);
  EXPECT_TRUE(open.front_outside.empty());
  const Octree t = build(torus(48, 24));
  const Octree back = through_store(t, "face_sides_torus");
  ASSERT_FALSE(t.front_outside.empty());
  EXPECT_EQ(back.front_outside, t.front_outside);
}

TEST(EbpFaceSides, TheSignFromTheFaceIsTheInsideQuerys) {
  std::vector<std::pair<std::string, Mesh>> meshes;
  for (const char* name : {"cow.obj", "fandisk.obj"}) meshes.push_back({name, bvhbench::load_mesh(shared_mesh(name))});
  meshes.push_back({"torus", torus(64, 32)});
  Mesh two;
  add_cube(two, {0, 0, 0}, 1.0, false);
  add_cube(two, {0.5, 0.25, 0.25}, 1.0, false);
  meshes.push_back({"two cubes", two});
  for (const auto& [name, m] : meshes) {
    SCOPED_TRACE(name);
    const Octree t = build(m);
    const Reference ref(m.vertices, m.triangles);
    // points near the surface (where the face decides) and far from it, in path order
    const std::vector<Vec3d> pts = sample_points(ref, 300, 1500, 11);
    // plain; coherent; coherent with certificates as the policy chooses them; always
    for (const int variant : {0, 1, 2, 3}) {
      SCOPED_TRACE("variant " + std::to_string(variant));
      const bool coherent = variant > 0;
      Query with(t, coherent), without(t, coherent);
      for (Query* q : {&with, &without}) {
        q->set_certificate(variant >= 2);
        q->set_adaptive_certificate(variant == 2);
      }
      without.set_face_sign(false);
      for (const Vec3d& p0 : pts) {
        const Vec3d p = t.to_frame(p0);
        const DistanceAnswer a = with.distance(p), b = without.distance(p);
        ASSERT_EQ(a.distance, b.distance) << p0.x << " " << p0.y << " " << p0.z;
        ASSERT_EQ(a.triangle, b.triangle);
        ASSERT_EQ(a.distance < 0, ref.winding(p0) > 0.5) << p0.x << " " << p0.y << " " << p0.z;
      }
      EXPECT_GT(with.counters.signs_from_face, pts.size() / 4);
      EXPECT_EQ(without.counters.signs_from_face, 0u);
    }
  }
}
