// What is particular to embree: the size of its scene and the work its BVH saves, and the rays
// an inside vote shoots.
//
// Answers are checked elsewhere: the default and coherent=true builds by the method-conformance
// suite (tests/cpp/methods/test_conformance.cpp), as every registered method is; the quality,
// robust and rays variants by tests/cpp/methods/test_parameter_variants.cpp.
#include <gtest/gtest.h>

#include <string>

#include "harness/core/mesh.hpp"
#include "harness/core/registry.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

#define SKIP_WITHOUT_EMBREE() \
  if (!Registry::global().find("embree")) GTEST_SKIP() << "embree method not built"

// Deterministic counters are the conformance suite's; here, what the BVH is and saves.
TEST(Embree, CountersAndBytes) {
  SKIP_WITHOUT_EMBREE();
  const Mesh s = icosphere(3);
  auto d = build_method("embree", s, QueryType::distance);
  EXPECT_GT(d->structure_bytes(), s.triangles.size() * 12 + s.vertices.size() * 12);  // + the BVH
  const auto queries = sample_queries(s, 20, 0, 1);
  auto c = counter_values(count_distance_pass(*d, queries));
  EXPECT_GT(c["triangles_tested"], 0u);
  EXPECT_EQ(c["point_queries"], 20u);
  EXPECT_LT(c["triangles_tested"], 20u * s.triangles.size());  // the tree prunes
}

TEST(Embree, VotesShootOneRayEachAtLeast) {
  SKIP_WITHOUT_EMBREE();
  const Mesh s = icosphere(2);
  for (int rays : {1, 3, 5}) {
    auto in = build_method("embree:rays=" + std::to_string(rays), s, QueryType::inside);
    in->reset_counters();
    EXPECT_TRUE(in->inside({0.1, 0.2, 0.3}));
    EXPECT_FALSE(in->inside({0.9, 0.9, 0.9}));  // in the box, outside the sphere: rays needed
    auto c = counter_values(*in);
    EXPECT_GE(c["rays_shot"], 2u * unsigned(rays));
    EXPECT_EQ(c["undecided"], 0u);
  }
}
