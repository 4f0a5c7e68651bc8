// The near set (core/near_set.hpp) and the coherent distance's near start: a gathered set holds
// every triangle whose box meets its box, each once (zero-area ones when asked); a coherent
// search along a contact path answers from it most of the time, and its answers are the tree
// search's and brute force's bit for bit, on real meshes and on stress meshes.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/core/mesh.hpp"
#include "harness/core/query_set.hpp"
#include "harness/io/mesh_io.hpp"
#include "methods/ebp_octree/build/octree_build.hpp"
#include "methods/ebp_octree/core/near_set.hpp"
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/core/query.hpp"
#include "methods/ebp_octree/ebp_test_support.hpp"
#include "methods/ebp_octree/store/out_of_core.hpp"
#include "methods/ebp_octree/store/writer.hpp"
#include "support/test_support.hpp"

using namespace ebp_test;

namespace {

bool bits_eq(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

/// Whether input triangle i's float box (in the tree's frame) meets the closed float box [lo, hi].
bool box_meets(const Octree& t, const Mesh& m, std::size_t i, const float lo[3], const float hi[3]) {
  float a[3][3];
  for (int k = 0; k < 3; ++k) {
    const Vec3d v = t.to_frame(m.vertices[m.triangles[i][std::size_t(k)]]);
    a[k][0] = float(v.x), a[k][1] = float(v.y), a[k][2] = float(v.z);
  }
  for (int ax = 0; ax < 3; ++ax)
    if (std::max({a[0][ax], a[1][ax], a[2][ax]}) < lo[ax] || std::min({a[0][ax], a[1][ax], a[2][ax]}) > hi[ax])
      return false;
  return true;
}

/// The harness's contact path (`bvhbench queries --kind contact`) of n points on `m`.
std::vector<Vec3d> contact(const Mesh& m, std::size_t n, double band_mm, double slide_speed) {
  nlohmann::json meta;
  return bvhbench::generate_queries(m, "contact", n, 1, {{"band_mm", band_mm}, {"slide_speed", slide_speed}}, &meta);
}

/// Whether two answers are the same bit for bit (distance, triangle, closest point).
bool same_answer(const DistanceAnswer& a, const DistanceAnswer& b) {
  return bits_eq(a.distance, b.distance) && a.triangle == b.triangle && bits_eq(a.closest.x, b.closest.x) &&
         bits_eq(a.closest.y, b.closest.y) && bits_eq(a.closest.z, b.closest.z);
}

/// The harness's contact path on the tree's mesh, in the tree's frame (where Query works).
std::vector<Vec3d> contact_in_frame(const Octree& t, const Mesh& m, std::size_t n, double band_mm, double speed) {
  std::vector<Vec3d> path = contact(m, n, band_mm, speed);
  for (Vec3d& q : path) q = t.to_frame(q);
  return path;
}

}  // namespace

// Boxes of several sizes about points near the surface: a gathered set holds exactly the
// triangles whose float boxes meet its box, each input triangle once; a box wider than two leaf
// cells is refused, and so is one that meets more than its limit of triangles (both limits the
// queries use: the set's capacity, and half of it, which takes the smaller table of seen indices).
TEST(EbpNearSet, GatherHoldsEveryTriangleMeetingItsBox) {
  for (const std::uint32_t limit : {kNearMax / 2, kNearMax}) {
    for (const char* name : {"cow.obj", "fandisk.obj"}) {
      const Mesh m = bvhbench::load_mesh(shared_mesh(name));
      const Octree t = build(m);
      const Reference ref(m.vertices, m.triangles);
      const double cell = t.cell_size(t.leaf_level);
      const auto pts = sample_points(ref, 0, 200, 3);
      int gathered = 0, refused_big = 0;
      for (std::size_t i = 0; i < pts.size(); ++i) {
        const Vec3d p = t.to_frame(pts[i]);
        const double h = cell * std::array<double, 4>{0.01, 0.1, 0.4, 1.5}[i % 4];
        NearSet ns;
        const bool ok = ns.gather(t, p - Vec3d(h, h, h), p + Vec3d(h, h, h), UINT32_MAX, true, limit);
        std::set<std::uint32_t> want;
        if (h < 0.5 * cell || ok) {
          for (std::size_t k = 0; k < m.triangles.size(); ++k)
            if (box_meets(t, m, k, ns.lo, ns.hi)) want.insert(std::uint32_t(k));
        }
        if (!ok) {
          EXPECT_FALSE(ns.valid);
          // refused only for a reason: more than two cells on an axis, a box leaving the root
          // cube, or too many triangles
          bool leaves_root = false;
          for (int a = 0; a < 3; ++a)
            leaves_root |= p[a] - h < t.root_lo[a] || p[a] + h > t.root_lo[a] + t.root_size;
          if (h > 0.5 * cell) {
            ++refused_big;
          } else if (!leaves_root) {
            EXPECT_GT(want.size(), limit) << name << " point " << i;
            EXPECT_TRUE(ns.overflowed) << name << " point " << i;
          }
          continue;
        }
        ++gathered;
        ASSERT_TRUE(ns.valid);
        EXPECT_LE(ns.n, limit);
        EXPECT_LE(ns.lo[0], p.x - h);
        EXPECT_GE(ns.hi[2], p.z + h);
        std::set<std::uint32_t> got;
        for (std::uint32_t j = 0; j < ns.n; ++j) {
          EXPECT_TRUE(got.insert(t.tris[ns.k[j]].tri()).second) << name << ": a triangle twice";
          EXPECT_EQ(t.nodes[ns.node[j]].index, ns.leaf[j]);
          const LeafTri& lt = t.tris[ns.k[j]];
          EXPECT_TRUE(ns.k[j] >= t.leaves[ns.leaf[j]].tri_begin &&
                      ns.k[j] < t.leaves[ns.leaf[j]].tri_begin + t.leaves[ns.leaf[j]].tri_count);
          for (int a = 0; a < 3; ++a) {  // its box: the min and max of its float vertices
            EXPECT_EQ(ns.blo[a][j], std::min({lt.a[a], lt.b[a], lt.c[a]})) << name << " member " << j;
            EXPECT_EQ(ns.bhi[a][j], std::max({lt.a[a], lt.b[a], lt.c[a]})) << name << " member " << j;
          }
        }
        for (std::uint32_t j = ns.n; j % 8 != 0; ++j)  // padded to 8 with empty boxes
          for (int a = 0; a < 3; ++a) EXPECT_GT(ns.blo[a][j], ns.bhi[a][j]) << name << " padding " << j;
        EXPECT_EQ(got, want) << name << " point " << i << " half-width " << h;
      }
      EXPECT_GT(gathered, 80) << name;
      EXPECT_GT(refused_big, 0) << name;
    }
  }
}

// Zero-area triangles: in the set when asked (a distance needs them), left out otherwise (they
// cross nothing).
TEST(EbpNearSet, ZeroAreaTrianglesOnlyWhenAsked) {
  Mesh m = bvhbench::test::icosphere(2);
  const std::uint32_t v0 = m.triangles[5][0], v1 = m.triangles[5][1];
  m.triangles.push_back({v0, v1, v0});  // zero area: a repeated vertex
  const std::uint32_t sliver = std::uint32_t(m.triangles.size() - 1);
  const Octree t = build(m);
  const Vec3d p = t.to_frame((m.vertices[v0] + m.vertices[v1]) * 0.5);
  const double h = 1e-3;
  auto members = [&](bool with_degenerate) {
    NearSet ns;
    EXPECT_TRUE(ns.gather(t, p - Vec3d(h, h, h), p + Vec3d(h, h, h), UINT32_MAX, with_degenerate, kNearMax));
    std::set<std::uint32_t> s;
    for (std::uint32_t j = 0; j < ns.n; ++j) s.insert(t.tris[ns.k[j]].tri());
    return s;
  };
  EXPECT_EQ(members(true).count(sliver), 1u);
  EXPECT_EQ(members(false).count(sliver), 0u);
  EXPECT_EQ(members(true).size(), members(false).size() + 1);
}

// Contact paths (the probe within +-band of the surface, sliding) on the shared meshes: the
// coherent search answers most queries from its near set, bit for bit as the search without
// coherence and as brute force.
TEST(EbpNearSet, ContactPathsAreTheTreeSearchBitForBit) {
  for (const char* name : {"cow.obj", "fandisk.obj", "rocker-arm.obj"}) {
    const Mesh m = bvhbench::load_mesh(shared_mesh(name));
    const Octree t = build(m);
    std::vector<Vec3d> fv;
    for (const Vec3d& v : m.vertices) fv.push_back(t.to_frame(v));
    const Reference ref(fv, m.triangles);
    for (const auto& [band, speed] : std::vector<std::pair<double, double>>{{0.05, 0.1}, {0.5, 0.3}}) {
      const std::vector<Vec3d> path = contact_in_frame(t, m, 1500, band, speed);
      Query near(t, true), tree(t, false);
      near.set_certificate(false);
      for (std::size_t i = 0; i < path.size(); ++i) {
        const DistanceAnswer a = near.distance(path[i]), b = tree.distance(path[i]);
        ASSERT_TRUE(same_answer(a, b)) << name << " query " << i;
        if (i % 10 == 0) {  // brute force, every tenth
          std::int64_t bt;
          const double d = ref.dist(path[i], &bt);
          EXPECT_EQ(std::fabs(a.distance), d) << name << " query " << i;
        }
      }
      EXPECT_GT(near.counters.near_served, path.size() / 2) << name << " band " << band;
      EXPECT_GT(near.counters.near_gathered, 0u);
      EXPECT_LT(near.counters.nodes_visited, tree.counters.nodes_visited / 4) << name;
    }
  }
}

// Stress meshes (duplicates, zero-area triangles, a thin sheet, nested shells, far from the
// origin) along slow paths that graze them: the near start answers as the tree search does.
TEST(EbpNearSet, StressMeshesAreExact) {
  std::vector<std::pair<std::string, Mesh>> meshes;
  {
    Mesh m = bvhbench::test::icosphere(3);
    const std::size_t n = m.triangles.size();
    for (std::size_t i = 0; i < n; i += 7) m.triangles.push_back(m.triangles[i]);
    for (std::size_t i = 0; i < n; i += 11) m.triangles.push_back({m.triangles[i][0], m.triangles[i][1], m.triangles[i][0]});
    meshes.push_back({"duplicates and degenerate", m});
  }
  {
    Mesh m = bvhbench::test::unit_cube();
    for (Vec3d& v : m.vertices) v.z *= 1e-4;
    meshes.push_back({"thin sheet", m});
  }
  {
    Mesh m = bvhbench::test::icosphere(2), in = bvhbench::test::icosphere(2, 0.98);
    const std::uint32_t off = std::uint32_t(m.vertices.size());
    m.vertices.insert(m.vertices.end(), in.vertices.begin(), in.vertices.end());
    for (auto f : in.triangles) m.triangles.push_back({f[0] + off, f[2] + off, f[1] + off});
    meshes.push_back({"nested shells 2 % apart", m});
  }
  {
    Mesh m = bvhbench::test::icosphere(3);
    for (Vec3d& v : m.vertices) v += Vec3d(1e6, -2e6, 5e5);
    meshes.push_back({"far from the origin", m});
  }
  for (const auto& [name, m] : meshes) {
    const Octree t = build(m);
    const std::vector<Vec3d> path = contact_in_frame(t, m, 2000, 0.2, 0.1);
    Query near(t, true), tree(t, false);
    near.set_certificate(false);
    for (std::size_t i = 0; i < path.size(); ++i)
      ASSERT_TRUE(same_answer(near.distance(path[i]), tree.distance(path[i]))) << name << " query " << i;
    EXPECT_GT(near.counters.near_served, 0u) << name;
  }
}

// Out of core: the previous page's near start answers most searches of a contact path (the
// other pages are not visited), bit for bit as the in-memory search without coherence, with
// small pages (so that balls often leave a page) and a cache that evicts.
TEST(EbpNearSet, OutOfCorePagesAnswerBitForBit) {
  const Mesh m = bvhbench::load_mesh(shared_mesh("fandisk.obj"));
  BuildParams bp;
  bp.threads = 1;
  const Octree t = build_octree(m.vertices, m.triangles, bp);
  bvhbench::test::TmpDir d("ebp_near_test");
  StoreWriteOptions o;
  o.page_target = 4096;
  write_store_atomic(t, d.file("f.ebp"), o);
  const std::vector<Vec3d> path = contact(m, 3000, 0.2, 0.1);  // world coordinates: OutOfCore's
  Query tree(t, false);
  OutOfCore ooc(d.file("f.ebp"), 64 << 10, true, false);
  ooc.set_certificate(false);
  for (std::size_t i = 0; i < path.size(); ++i)
    ASSERT_TRUE(same_answer(tree.distance(t.to_frame(path[i])), ooc.distance(path[i]))) << "query " << i;
  const QueryCounters k = ooc.counters();
  EXPECT_GT(k.near_served, path.size() / 3);
  EXPECT_GT(ooc.cache().evictions, 0u);
}

// Small triangles: where sets of the usual limit overflow until the path's scale is down to a
// quarter, the distance's sets take up to kNearMax members, and answer bit for bit as the search
// without coherence and as brute force.
TEST(EbpNearSet, SmallTrianglesTakeLargerSets) {
  const Mesh m = bvhbench::test::icosphere(6);  // 81,920 triangles on the unit sphere
  const Octree t = build(m);
  std::vector<Vec3d> fv;
  for (const Vec3d& v : m.vertices) fv.push_back(t.to_frame(v));
  const Reference ref(fv, m.triangles);
  const std::vector<Vec3d> path = contact_in_frame(t, m, 2000, 20, 0.3);
  Query near(t, true), tree(t, false);
  near.set_certificate(false);
  std::uint32_t largest = 0;
  for (std::size_t i = 0; i < path.size(); ++i) {
    const DistanceAnswer a = near.distance(path[i]);
    ASSERT_TRUE(same_answer(a, tree.distance(path[i]))) << "query " << i;
    if (const NearSet* ns = near.distance_near_set(); ns && ns->valid) largest = std::max(largest, ns->n);
    if (i % 10 == 0) {
      std::int64_t bt;
      EXPECT_EQ(std::fabs(a.distance), ref.dist(path[i], &bt)) << "query " << i;
    }
  }
  EXPECT_GT(largest, kNearMax / 2);
  EXPECT_LE(largest, kNearMax);
  EXPECT_GT(near.counters.near_served, path.size() / 4);
}
