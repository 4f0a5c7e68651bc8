// Octcodes (core/octcode.hpp): round trips and pre-order.
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
#include "methods/ebp_octree/core/octcode.hpp"
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/ebp_test_support.hpp"

using namespace ebp_test;

// ---------------------------------------------------------------------------------------------
TEST(EbpOctcode, RoundTripsAndOrder) {
  std::mt19937 rng(7);
  for (int l = 0; l <= kMaxLevel; ++l) {
    for (int k = 0; k < 200; ++k) {
      const std::uint32_t mask = l == 0 ? 0 : (1u << l) - 1;
      const std::uint32_t x = rng() & mask, y = rng() & mask, z = rng() & mask;
      const Octcode c = octcode_from_cell(l, x, y, z);
      std::uint32_t a, b, d;
      octcode_cell(c, &a, &b, &d);
      EXPECT_EQ(a, x); EXPECT_EQ(b, y); EXPECT_EQ(d, z);
      EXPECT_EQ(octcode_level(c), l);
      if (l > 0) {
        const Octcode p = octcode_parent(c);
        EXPECT_EQ(octcode_level(p), l - 1);
        EXPECT_EQ(octcode_child(p, octcode_octant(c)), c);
        EXPECT_LT(p, c);  // pre-order: the parent first
        EXPECT_TRUE(octcode_contains(p, c));
        EXPECT_LT(c, octcode_subtree_end(p));
      }
      if (l < kMaxLevel)
        for (int o = 0; o < 8; ++o) {
          const Octcode ch = octcode_child(c, o);
          EXPECT_GT(ch, c);
          EXPECT_LT(ch, octcode_subtree_end(c));
          if (o > 0) {
            EXPECT_GE(ch, octcode_subtree_end(octcode_child(c, o - 1)));
          }
        }
    }
  }
  EXPECT_EQ(octcode_level(octcode_root()), 0);
  EXPECT_EQ(morton_encode(1, 0, 0), 1u);
  EXPECT_EQ(morton_encode(0, 1, 0), 2u);
  EXPECT_EQ(morton_encode(0, 0, 1), 4u);
  const std::uint32_t big = (1u << 19) - 1;
  std::uint32_t a, b, d;
  morton_decode(morton_encode(big, 0, big), &a, &b, &d);
  EXPECT_EQ(a, big); EXPECT_EQ(b, 0u); EXPECT_EQ(d, big);
}
