// The exact predicates (core/predicates.hpp): orientation sign convention and exactness.
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
#include "methods/ebp_octree/core/predicates.hpp"
#include "methods/ebp_octree/ebp_test_support.hpp"

using namespace ebp_test;

TEST(EbpPredicates, OrientSignConventionAndExactness) {
  const Vec3d a{0, 0, 0}, b{1, 0, 0}, c{0, 1, 0};
  EXPECT_EQ(orient3d(a, b, c, {0, 0, 1}), 1);  // the side the right-hand normal points to
  EXPECT_EQ(orient3d(a, b, c, {0, 0, -1}), -1);
  EXPECT_EQ(orient3d(a, b, c, {0.3, 0.3, 0}), 0);
  EXPECT_EQ(orient3d_exact(a, b, c, {0, 0, 1}), 1);
  // Nearly coplanar: the filter must defer to the exact path and agree with it.
  const Vec3d p{0.1, 0.2, 1e-300};
  EXPECT_EQ(orient3d(a, b, c, p), 1);
  const Vec3d q1{0.1, 0.1, 0.1}, q2{0.7, 0.3, 0.9}, q3{0.2, 0.8, 0.4};
  const Vec3d m = (q1 + q2) * 0.5;  // rounding makes this nearly but not necessarily on the line
  EXPECT_EQ(orient3d(q1, q2, q3, m), orient3d_exact(q1, q2, q3, m));
  EXPECT_TRUE(collinear_exact({0, 0, 0}, {1, 1, 1}, {2, 2, 2}));
  EXPECT_FALSE(collinear_exact({0, 0, 0}, {1, 1, 1}, {2, 2, 2.0000001}));
}
