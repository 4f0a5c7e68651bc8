// The ebp_octree method through the registry (ebp_method.cpp) against brute_force.
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
#include "harness/core/registry.hpp"
#include "harness/io/mesh_io.hpp"
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/core/query.hpp"
#include "methods/ebp_octree/ebp_test_support.hpp"

using namespace ebp_test;

// The method through the registry, against the brute_force method, as the harness runs them.
TEST(EbpMethod, RegistryAdapterMatchesBruteForce) {
  const bvhbench::Registry& reg = bvhbench::Registry::global();
  ASSERT_NE(reg.find("ebp_octree"), nullptr);
  Mesh m = bvhbench::load_mesh(shared_mesh("fandisk.obj"));
  auto ebp = reg.create("ebp_octree:coherent=true,leaf_factor=4");
  auto bf = reg.create("brute_force");
  bvhbench::BuildContext ctx;
  ebp->build(m, ctx);
  bf->build(m, ctx);
  const Reference ref(m.vertices, m.triangles);
  const double diag = ref.bounds().diagonal();
  m = Mesh{};  // the harness releases the mesh after build
  ebp->reset_path();
  ebp->reset_counters();
  int n = 0;
  for (const Vec3d& p : sample_points(ref, 100, 200, 8)) {
    const bvhbench::DistanceResult want = bf->distance(p);
    if (std::fabs(want.distance) < 1e-6 * diag) continue;
    EXPECT_EQ(ebp->inside(p), bf->inside(p));
    const bvhbench::DistanceResult got = ebp->distance(p);
    EXPECT_NEAR(got.distance, want.distance, 1e-5 * diag);
    EXPECT_NEAR(ref.tri_dist(p, got.triangle), std::fabs(want.distance), 1e-5 * diag);
    ++n;
  }
  EXPECT_GT(n, 250);
  EXPECT_GT(ebp->structure_bytes(), 0u);
  EXPECT_TRUE(ebp->info().contains("tightness"));
  // The bytes' breakdown accounts for all of them but the tree's own record.
  const nlohmann::json info = ebp->info();
  std::size_t parts = 0;
  for (const auto& [name, part] : info["bytes_breakdown"].items()) parts += part["bytes"].get<std::size_t>();
  EXPECT_EQ(parts + sizeof(ebp::Octree), info["bytes"].get<std::size_t>());
  EXPECT_GT(info["bytes_breakdown"]["sub_references"]["bytes"].get<std::size_t>(), 0u);  // fandisk is closed
  bool has_nodes = false;
  for (auto& c : ebp->counters()) has_nodes |= c.name == "nodes_visited" && c.value > 0;
  EXPECT_TRUE(has_nodes);
}
