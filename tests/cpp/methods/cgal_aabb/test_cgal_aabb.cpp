// What is particular to cgal_aabb: the size of its tree and the work it saves.
//
// Answers are checked elsewhere: the default and coherent=true builds by the method-conformance
// suite (tests/cpp/methods/test_conformance.cpp), as every registered method is; the kernel and
// kd_tree variants by tests/cpp/methods/test_parameter_variants.cpp.
#include <gtest/gtest.h>

#include "harness/core/mesh.hpp"
#include "harness/core/registry.hpp"
#include "support/test_support.hpp"

using namespace bvhbench;
using namespace bvhbench::test;

// Deterministic counters are the conformance suite's; here, what the tree is and saves.
TEST(CgalAabb, CountersAndBytes) {
  if (!Registry::global().find("cgal_aabb")) GTEST_SKIP() << "cgal_aabb method not built";
  const Mesh s = icosphere(3);
  auto d = build_method("cgal_aabb", s, QueryType::distance);
  EXPECT_GT(d->structure_bytes(), s.triangles.size() * (12 + 4 + 64));  // geometry + ids + nodes
  const auto queries = sample_queries(s, 20, 0, 1);
  auto c = counter_values(count_distance_pass(*d, queries));
  EXPECT_GT(c["triangles_tested"], 0u);
  EXPECT_GT(c["nodes_visited"], 0u);
  EXPECT_LT(c["triangles_tested"], 20u * s.triangles.size());  // the tree prunes
}
