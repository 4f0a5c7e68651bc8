// The in-memory builder (build/octree_build.cpp): distribution of triangles to leaves,
// containment by the bounding planes, the parallel build identical to the serial one.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "harness/core/mesh.hpp"
#include "harness/io/mesh_io.hpp"
#include "methods/ebp_octree/build/tri_box.hpp"
#include "methods/ebp_octree/core/octcode.hpp"
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/ebp_test_support.hpp"

using namespace ebp_test;

// Every triangle is listed in exactly the leaf cells it touches (by the overlap test of every
// (triangle, cell) pair around it).
TEST(EbpBuild, DistributionIsExactOnCow) {
  const Mesh m = bvhbench::load_mesh(shared_mesh("cow.obj"));
  const Octree t = build(m);
  const int L = t.leaf_level;
  EXPECT_GE(L, 1);
  std::map<std::uint32_t, std::set<std::uint64_t>> listed;
  for (const Node& nd : t.nodes) {
    if (nd.kind != NodeKind::leaf) continue;
    EXPECT_EQ(octcode_level(nd.code), L);
    const Leaf& lf = t.leaves[nd.index];
    for (std::uint32_t k = 0; k < lf.tri_count; ++k) listed[t.tris[lf.tri_begin + k].tri()].insert(octcode_morton(nd.code));
  }
  const double cs = t.cell_size(L);
  const std::uint32_t G = 1u << L;
  std::size_t pairs = 0;
  for (std::uint32_t i = 0; i < m.triangles.size(); ++i) {
    Vec3d v[3];
    Box3d b;
    for (int k = 0; k < 3; ++k) {
      const Vec3d p = m.vertices[m.triangles[i][k]];
      v[k] = round_to_float(p);
      b.add(v[k]);
    }
    std::set<std::uint64_t> expect;
    auto lo_i = [&](int a) { return std::uint32_t(std::max(0.0, std::floor((b.lo[a] - t.root_lo[a]) / cs) - 1)); };
    auto hi_i = [&](int a) { return std::min(G - 1, std::uint32_t(std::floor((b.hi[a] - t.root_lo[a]) / cs) + 1)); };
    for (std::uint32_t z = lo_i(2); z <= hi_i(2); ++z)
      for (std::uint32_t y = lo_i(1); y <= hi_i(1); ++y)
        for (std::uint32_t x = lo_i(0); x <= hi_i(0); ++x) {
          Vec3d clo, chi;
          t.cell_box(octcode_from_cell(L, x, y, z), &clo, &chi);
          if (tri_box_overlap(clo, chi, v[0], v[1], v[2])) expect.insert(morton_encode(x, y, z));
        }
    pairs += expect.size();
    ASSERT_EQ(listed[i], expect) << "triangle " << i;
  }
  EXPECT_EQ(pairs, t.tris.size());
}

// Every bounding plane of every grey node contains its geometry: every vertex of every
// triangle ∩ cell polygon is on the inner side, with tolerance 0 (in double).
TEST(EbpBuild, BoundingPlanesContainTheGeometry) {
  for (const char* name : {"cow.obj", "fandisk.obj"}) {
    const Mesh m = bvhbench::load_mesh(shared_mesh(name));
    const Octree t = build(m);
    std::size_t checked = 0;
    for (std::size_t i = 0; i < t.nodes.size(); ++i) {
      const Node& nd = t.nodes[i];
      if (nd.kind != NodeKind::leaf && nd.kind != NodeKind::inner) continue;
      Vec3d lo, hi;
      t.cell_box(nd.code, &lo, &hi);
      std::vector<Vec3d> pts;
      for (std::size_t j = i; j < nd.next; ++j) {
        if (t.nodes[j].kind != NodeKind::leaf) continue;
        const Leaf& lf = t.leaves[t.nodes[j].index];
        for (std::uint32_t k = 0; k < lf.tri_count; ++k) {
          const LeafTri& r = t.tris[lf.tri_begin + k];
          const auto poly = clip_exact(lo, hi, {r.a[0], r.a[1], r.a[2]}, {r.b[0], r.b[1], r.b[2]}, {r.c[0], r.c[1], r.c[2]});
          pts.insert(pts.end(), poly.begin(), poly.end());
        }
      }
      for (std::uint32_t k = 0; k < nd.plane_count; ++k) {
        const Plane& pl = t.planes[nd.plane_begin + k];
        const Vec3d n{pl.n[0], pl.n[1], pl.n[2]};
        for (const Vec3d& v : pts) {
          ASSERT_LE(dot(n, v - t.root_centre), double(pl.d)) << name << " node " << i << " plane " << k;
          ++checked;
        }
      }
    }
    EXPECT_GT(checked, 1000u) << name;
    EXPECT_GT(t.stats.planes, 0u);
    EXPECT_LT(t.stats.leaf_volume, t.stats.leaf_box_volume);
  }
}

TEST(EbpBuild, ParallelBuildIsIdentical) {
  const Mesh m = bvhbench::load_mesh(shared_mesh("fandisk.obj"));
  BuildParams bp;
  const Octree a = build(m, bp);
  bp.threads = 2;
  const Octree b = build(m, bp);
  ASSERT_EQ(a.nodes.size(), b.nodes.size());
  ASSERT_EQ(a.tris.size(), b.tris.size());
  ASSERT_EQ(a.planes.size(), b.planes.size());
  for (std::size_t i = 0; i < a.nodes.size(); ++i) {
    ASSERT_EQ(a.nodes[i].code, b.nodes[i].code);
    ASSERT_EQ(a.nodes[i].kind, b.nodes[i].kind);
  }
  for (std::size_t i = 0; i < a.planes.size(); ++i) ASSERT_EQ(a.planes[i].d, b.planes[i].d);
}
