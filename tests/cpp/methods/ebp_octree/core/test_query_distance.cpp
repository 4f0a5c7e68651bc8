// Distance (core/query.cpp) against a brute-force reference: the lexicographic minimum bit
// for bit, and the branch-and-bound entry point Query::distance_bound.
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
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/core/query.hpp"
#include "methods/ebp_octree/ebp_test_support.hpp"

using namespace ebp_test;

TEST(EbpQuery, DistanceMatchesReference) {
  for (const char* name : {"cow.obj", "rocker-arm.obj", "stanford-bunny.obj"}) {
    const Mesh m = bvhbench::load_mesh(shared_mesh(name));
    const Octree t = build(m);
    const Reference ref(m.vertices, m.triangles);
    const double diag = ref.bounds().diagonal();
    const bool closed = std::string(name) != "stanford-bunny.obj";
    const auto pts = sample_points(ref, 150, 250, 99);
    Query q(t, false);
    for (const Vec3d& p : pts) {
      std::int64_t bt;
      const double want = ref.dist(p, &bt);
      const DistanceAnswer a = q.distance(p);
      ASSERT_NEAR(std::fabs(a.distance), want, 1e-5 * diag) << name;
      // The same triangle, or one exactly as close (ties).
      EXPECT_NEAR(ref.tri_dist(p, a.triangle), want, 1e-12 * diag) << name;
      EXPECT_NEAR(norm(a.closest - p), want, 1e-9 * diag);
      const auto& tr = ref.f[std::size_t(a.triangle)];
      const Vec3d n = bvhbench::triangle_normal(ref.v[tr[0]], ref.v[tr[1]], ref.v[tr[2]]);
      EXPECT_NEAR(norm(a.normal - n), 0.0, 1e-9);
      if (closed && want > 1e-6 * diag) {
        EXPECT_EQ(a.distance < 0, ref.winding(p) > 0.5) << name;
      }
    }
  }
}

// The answer is the brute-force lexicographic minimum of (squared distance, triangle index),
// bit for bit, near and far from the surface, on the boundaries of leaf cells (where the located
// start picks one side), in empty cells and outside the root (where it dives or stands aside),
// coherent or not.
TEST(EbpQuery, DistanceIsTheLexicographicMinimumBitForBit) {
  for (const char* name : {"cow.obj", "fandisk.obj"}) {
    const Mesh m = bvhbench::load_mesh(shared_mesh(name));
    const Octree t = build(m);
    const Reference ref(m.vertices, m.triangles);
    auto pts = sample_points(ref, 150, 250, 7);
    const Box3d bb = ref.bounds();
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-3, 4);
    for (int i = 0; i < 100; ++i) {  // far points
      const Vec3d e = bb.extent();
      pts.push_back({bb.lo.x + u(rng) * e.x, bb.lo.y + u(rng) * e.y, bb.lo.z + u(rng) * e.z});
    }
    for (std::size_t i = 0; i < t.nodes.size(); i += 3) {  // corners and face centres of cells
      Vec3d lo, hi;
      t.cell_box(t.nodes[i].code, &lo, &hi);
      pts.push_back(lo);
      pts.push_back({0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), lo.z});
    }
    for (bool coherent : {false, true}) {
      Query q(t, coherent);
      for (const Vec3d& p : pts) {
        double best2 = std::numeric_limits<double>::infinity();
        std::int64_t bi = -1;
        Vec3d bq;
        for (std::size_t i = 0; i < ref.f.size(); ++i) {
          const Vec3d c = bvhbench::closest_point_on_triangle(p, ref.v[ref.f[i][0]], ref.v[ref.f[i][1]], ref.v[ref.f[i][2]]);
          const double d2 = squared_norm(c - p);
          if (d2 < best2) { best2 = d2; bi = std::int64_t(i); bq = c; }
        }
        const DistanceAnswer a = q.unsigned_distance(p);
        ASSERT_EQ(a.triangle, bi) << name;
        ASSERT_EQ(a.distance, std::sqrt(best2)) << name;
        ASSERT_EQ(a.closest, bq) << name;
      }
    }
  }
}

// distance_bound: an initial bound >= the true distance changes nothing; the true answer as the
// initial bound is kept (nothing is strictly better); a subtree search finds the best of its
// leaves' triangles.
TEST(EbpQuery, DistanceBoundEntryPoint) {
  const Mesh m = bvhbench::load_mesh(shared_mesh("cow.obj"));
  const Octree t = build(m);
  const Reference ref(m.vertices, m.triangles);
  const auto pts = sample_points(ref, 100, 150, 5);
  Query q(t, false);
  for (const Vec3d& p : pts) {
    const DistanceAnswer a = q.unsigned_distance(p);
    for (double f : {1.0, 1.0 + 1e-9, 2.0}) {
      DistanceBest b;
      b.best = a.distance * f;
      b.best2 = b.best * b.best;
      if (f == 1.0) b.best2 = squared_norm(a.closest - p);
      b.key = UINT64_MAX;  // any triangle at exactly the bound wins the tie
      q.distance_bound(p, b, DistanceStart{});
      ASSERT_NE(b.k, UINT32_MAX);
      ASSERT_EQ(std::int64_t(t.tris[b.k].tri()), a.triangle);
      ASSERT_EQ(b.best, a.distance);
      ASSERT_EQ(b.closest, a.closest);
    }
    DistanceBest b;  // the answer itself: nothing is strictly better
    b.best2 = squared_norm(a.closest - p);
    b.best = std::sqrt(b.best2);
    b.key = std::uint64_t(a.triangle);
    q.distance_bound(p, b, DistanceStart{});
    EXPECT_EQ(b.k, UINT32_MAX);
    EXPECT_EQ(b.key, std::uint64_t(a.triangle));
  }
  // Subtrees: the root's grey children, each against brute force over its leaves' triangles.
  int inside_cell = 0;
  const Node& root = t.nodes[0];
  ASSERT_EQ(root.kind, NodeKind::inner);
  for (int o = 0; o < 8; ++o) {
    const std::uint32_t c = t.children[root.index + o];
    if (t.nodes[c].kind != NodeKind::inner && t.nodes[c].kind != NodeKind::leaf) continue;
    std::set<std::uint32_t> sub;
    for (std::uint32_t i = c; i < t.nodes[c].next; ++i)
      if (t.nodes[i].kind == NodeKind::leaf) {
        const Leaf& lf = t.leaves[t.nodes[i].index];
        for (std::uint32_t k = 0; k < lf.tri_count; ++k) sub.insert(t.tris[lf.tri_begin + k].tri());
      }
    for (std::size_t j = 0; j < pts.size(); j += 5) {
      const Vec3d& p = pts[j];
      double best2 = std::numeric_limits<double>::infinity();
      std::uint32_t bi = 0;
      for (std::uint32_t i : sub) {
        const auto& f = ref.f[i];
        const double d2 = squared_norm(bvhbench::closest_point_on_triangle(p, ref.v[f[0]], ref.v[f[1]], ref.v[f[2]]) - p);
        if (d2 < best2) { best2 = d2; bi = i; }
      }
      DistanceBest b;
      DistanceStart s;
      s.node = c;
      q.distance_bound(p, b, s);
      ASSERT_NE(b.k, UINT32_MAX);
      ASSERT_TRUE(sub.count(t.tris[b.k].tri()));
      // The subtree stands for its triangles within its cell: at least the best listed one, and
      // exactly it when its closest point is in the cell.
      ASSERT_GE(b.best2, best2);
      const auto& f = ref.f[bi];
      const Vec3d cp = bvhbench::closest_point_on_triangle(p, ref.v[f[0]], ref.v[f[1]], ref.v[f[2]]);
      Vec3d lo, hi;
      t.cell_box(t.nodes[c].code, &lo, &hi);
      if (cp.x >= lo.x && cp.y >= lo.y && cp.z >= lo.z && cp.x <= hi.x && cp.y <= hi.y && cp.z <= hi.z) {
        ASSERT_EQ(t.tris[b.k].tri(), bi);
        ASSERT_EQ(b.best2, best2);
        ++inside_cell;
      }
    }
  }
  EXPECT_GT(inside_cell, 10);
}
