// The conservative triangle/box overlap test (build/tri_box.hpp) against exact clipping.
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
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/ebp_test_support.hpp"

using namespace ebp_test;

// The overlap test against a clipping reference, on random and on touching configurations.
TEST(EbpTriBox, OverlapAgainstClippingReference) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> U(-1.5, 1.5);
  auto ref_touch = [](const Vec3d& lo, const Vec3d& hi, const Vec3d& a, const Vec3d& b, const Vec3d& c, double grow) {
    return !clip_exact(lo, hi, a, b, c, grow).empty();
  };
  const Vec3d lo{-0.5, -0.5, -0.5}, hi{0.5, 0.5, 0.5};
  int overlaps = 0;
  for (int k = 0; k < 20000; ++k) {
    Vec3d a{U(rng), U(rng), U(rng)}, b{U(rng), U(rng), U(rng)}, c{U(rng), U(rng), U(rng)};
    if (k % 4 == 1) { a.x = 0.5; }                       // a vertex on a face plane
    if (k % 4 == 2) { a = {0.5, 0.5, U(rng)}; b.x = 0.5; }  // an edge in a face plane
    if (k % 4 == 3) { a = {0.5, 0.5, 0.5}; b = b * 0.3 + Vec3d(1, 1, 1); c = c * 0.3 + Vec3d(1, 1, 1); }  // touches a corner
    const bool got = tri_box_overlap(lo, hi, a, b, c);
    if (ref_touch(lo, hi, a, b, c, 0.0)) {
      EXPECT_TRUE(got) << "missed a touching triangle, case " << k;
      ++overlaps;
    }
    if (got) {
      EXPECT_TRUE(ref_touch(lo, hi, a, b, c, 1e-6)) << "listed a triangle far from the box, case " << k;
    }
  }
  EXPECT_GT(overlaps, 1000);
  // Exactly touching, exactly separated by a hair.
  EXPECT_TRUE(tri_box_overlap(lo, hi, {0.5, 0.5, 0.5}, {1, 2, 3}, {2, 1, 3}));
  EXPECT_FALSE(tri_box_overlap(lo, hi, {0.5001, 0.5, 0.5}, {1, 2, 3}, {2, 1, 3}));
  // Degenerate triangles.
  EXPECT_TRUE(tri_box_overlap(lo, hi, {0, 0, 0}, {0, 0, 0}, {0, 0, 0}));
  EXPECT_TRUE(tri_box_overlap(lo, hi, {-1, 0, 0}, {1, 0, 0}, {0, 0, 0}));
  EXPECT_FALSE(tri_box_overlap(lo, hi, {-1, 0.6, 0}, {1, 0.6, 0}, {0, 0.6, 0}));
}
