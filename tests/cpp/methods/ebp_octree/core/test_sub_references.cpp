// The inside query's sub-references (core/sub_references.hpp): on closed meshes each is strictly
// inside its octant of the leaf's cell, off every face plane of the leaf, its sides are the exact
// orientations and its winding number the mesh's at that point; the inside answers through them
// are those through the leaf's one reference point, bit for bit, and those of the brute-force
// winding number; an open mesh has none; the tree decoded from its store has the same ones.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "harness/io/mesh_io.hpp"
#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/core/predicates.hpp"
#include "methods/ebp_octree/core/query.hpp"
#include "methods/ebp_octree/core/sub_references.hpp"
#include "methods/ebp_octree/ebp_test_support.hpp"
#include "methods/ebp_octree/store/reader.hpp"
#include "methods/ebp_octree/store/writer.hpp"
#include "support/test_support.hpp"

using namespace ebp_test;

namespace {

std::vector<std::pair<std::string, Mesh>> closed_meshes() {
  std::vector<std::pair<std::string, Mesh>> meshes;
  for (const char* name : {"cow.obj", "fandisk.obj", "rocker-arm.obj"})
    meshes.push_back({name, bvhbench::load_mesh(shared_mesh(name))});
  meshes.push_back({"torus", torus(64, 32)});
  return meshes;
}

}  // namespace

TEST(EbpSubReferences, InsideTheirOctantOffEveryPlaneWithTheMeshsWindingNumber) {
  for (const auto& [name, m] : closed_meshes()) {
    SCOPED_TRACE(name);
    const Octree t = build(m);
    ASSERT_TRUE(t.closed);
    ASSERT_EQ(t.sub_refs.size(), 8 * t.leaves.size());
    ASSERT_EQ(t.sub_sides.size(), 8 * t.blocks.size());
    const Reference ref(m.vertices, m.triangles);
    const double half = 0.5 * t.cell_size(t.leaf_level);
    std::size_t valid = 0, grey = 0;
    for (std::size_t li = 0; li < t.leaves.size(); ++li) {
      const Leaf& lf = t.leaves[li];
      if (!lf.ref_valid || lf.tri_count == 0) continue;
      grey += 8;
      for (int o = 0; o < 8; ++o) {
        const SubRef& sr = t.sub_refs[li * 8 + std::size_t(o)];
        if (!sr.valid) continue;
        ++valid;
        const Vec3d r = to_d(sr.p);
        // In octant o of the cell (the leaf's centre is within float rounding of the cell's).
        for (int k = 0; k < 3; ++k) {
          const bool upper = (o >> k) & 1;
          const double c = double(lf.centre[k]);
          EXPECT_LT(std::fabs(r[k] - c), half) << "leaf " << li;
          EXPECT_EQ(r[k] >= c - 1e-9 * half, upper) << "leaf " << li << " octant " << o;
        }
        const LeafTri* blk = t.tris.data() + lf.tri_begin;
        for (std::uint32_t k = 0; k < lf.tri_count; ++k) {
          if (blk[k].flags() & kDegenerate) continue;
          const int side = orient3d(to_d(blk[k].a), to_d(blk[k].b), to_d(blk[k].c), r);
          ASSERT_NE(side, 0) << "leaf " << li;
          const std::uint8_t mask = t.sub_sides[(std::size_t(t.leaf_block[li]) + k / kBlockTris) * 8 + std::size_t(o)];
          EXPECT_EQ((mask >> (k % kBlockTris)) & 1u, side > 0 ? 1u : 0u) << "leaf " << li << " triangle " << k;
        }
        EXPECT_EQ(sr.winding, int(std::lround(ref.winding(t.to_world(r))))) << "leaf " << li << " octant " << o;
      }
    }
    EXPECT_GT(valid, grey * 9 / 10) << "most octants have one";
  }
}

TEST(EbpSubReferences, SameAnswersAsTheLeafsReferencePointAndTheBruteForce) {
  for (const auto& [name, m] : closed_meshes()) {
    SCOPED_TRACE(name);
    const Octree with = build(m);
    Octree without = with;
    without.sub_refs.clear();
    without.sub_sides.clear();
    const Reference ref(m.vertices, m.triangles);
    const double diag = ref.bounds().diagonal();
    std::vector<Vec3d> pts = sample_points(ref, 1500, 1500, 77);
    // Points on the leaves' octant planes and their sub-references' coordinates: ties of the
    // octant choice and segments from a sub-reference along a cell's midplane.
    std::mt19937_64 rng(5);
    for (std::size_t li = 0; li < with.leaves.size() && pts.size() < 4000; li += 3) {
      const Leaf& lf = with.leaves[li];
      const Vec3d c = to_d(lf.centre);
      const double h = 0.5 * with.cell_size(with.leaf_level);
      std::uniform_real_distribution<double> u(-h, h);
      pts.push_back(with.to_world({c.x, c.y + u(rng), c.z + u(rng)}));
      pts.push_back(with.to_world({c.x + u(rng), c.y, c.z}));
    }
    Query qa(with, false), qb(without, false);
    int differ = 0, wrong = 0, checked = 0;
    for (const Vec3d& p : pts) {
      const bool a = qa.inside(p), b = qb.inside(p);
      differ += a != b;
      if (ref.dist(p) < 1e-6 * diag) continue;
      ++checked;
      wrong += a != (ref.winding(p) > 0.5);
    }
    EXPECT_EQ(differ, 0);
    EXPECT_EQ(wrong, 0) << "over " << checked;
    EXPECT_LT(qa.counters.planes_tested, qb.counters.planes_tested) << "shorter segments test fewer planes";
  }
}

TEST(EbpSubReferences, NoneOnAnOpenMesh) {
  Mesh m = torus(32, 16);
  m.triangles.resize(m.triangles.size() - 5);  // a hole
  const Octree t = build(m);
  EXPECT_FALSE(t.closed);
  EXPECT_TRUE(t.sub_refs.empty());
  EXPECT_TRUE(t.sub_sides.empty());
}

TEST(EbpSubReferences, TheStoresTreeHasTheSameOnes) {
  const Mesh m = bvhbench::load_mesh(shared_mesh("cow.obj"));
  const Octree t = build(m);
  const Octree back = through_store(t, "subref_cow");
  ASSERT_FALSE(t.sub_refs.empty());
  ASSERT_EQ(back.sub_refs.size(), t.sub_refs.size());
  EXPECT_EQ(std::memcmp(back.sub_refs.data(), t.sub_refs.data(), t.sub_refs.size() * sizeof(SubRef)), 0);
  EXPECT_EQ(back.sub_sides, t.sub_sides);
}
