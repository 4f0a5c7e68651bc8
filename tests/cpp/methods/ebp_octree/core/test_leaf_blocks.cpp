// Leaf blocks and node boxes (core/leaf_blocks.hpp).
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
#include "methods/ebp_octree/core/leaf_blocks.hpp"
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/ebp_test_support.hpp"

using namespace ebp_test;

// Leaf blocks (leaf_blocks.hpp): each block box holds its triangles, each group box its blocks,
// each node box holds its
// leaves' triangles within their cells, a leaf block is ordered by its set alone (the same
// triangles, and any permutation of them orders to the same block).
TEST(EbpLeafBlocks, BoxesContainTheirGeometryAndOrderIsAPermutation) {
  const Mesh m = bvhbench::load_mesh(shared_mesh("cow.obj"));
  const Octree t = build(m);
  ASSERT_TRUE(has_leaf_blocks(t));
  auto inside = [](const BlockBox& b, const float* v) {
    for (int a = 0; a < 3; ++a)
      if (!(b.lo[a] <= v[a] && v[a] <= b.hi[a])) return false;
    return true;
  };
  std::mt19937_64 rng(3);
  std::size_t ordered = 0, grouped = 0;
  for (std::size_t li = 0; li < t.leaves.size(); ++li) {
    const Leaf& lf = t.leaves[li];
    ASSERT_EQ(t.leaf_block[li] + block_count(lf.tri_count),
              li + 1 < t.leaves.size() ? t.leaf_block[li + 1] : std::uint32_t(t.blocks.size()));
    for (std::uint32_t k = 0; k < lf.tri_count; ++k) {
      const LeafTri& r = t.tris[lf.tri_begin + k];
      const BlockBox& b = t.blocks[t.leaf_block[li] + k / kBlockTris];
      ASSERT_TRUE(inside(b, r.a) && inside(b, r.b) && inside(b, r.c)) << li << " " << k;
    }
    std::vector<LeafTri> blk(t.tris.begin() + lf.tri_begin, t.tris.begin() + lf.tri_begin + lf.tri_count);
    std::vector<LeafTri> sh = blk;
    std::shuffle(sh.begin(), sh.end(), rng);
    order_leaf_triangles(sh.data(), std::uint32_t(sh.size()));
    ASSERT_EQ(0, std::memcmp(sh.data(), blk.data(), blk.size() * sizeof(LeafTri))) << "leaf " << li;
    ordered += lf.tri_count > kBlockTris;
    // Groups: a leaf of more than kGroupBlocks blocks has one box per kGroupBlocks blocks, each
    // holding its blocks' boxes (the search skips a group whose box is apart from its ball).
    const std::uint32_t nb = block_count(lf.tri_count);
    if (nb <= kGroupBlocks) continue;
    ++grouped;
    const std::uint32_t ng = group_count(nb);
    ASSERT_LE(t.leaf_group[li] + ng, t.groups.size()) << li;
    for (std::uint32_t j = 0; j < nb; ++j) {
      const BlockBox& g = t.groups[t.leaf_group[li] + j / kGroupBlocks];
      const BlockBox& b = t.blocks[t.leaf_block[li] + j];
      ASSERT_TRUE(inside(g, b.lo) && inside(g, b.hi)) << li << " " << j;
    }
  }
  EXPECT_GT(ordered, 10u);
  EXPECT_GT(grouped, 0u);
  // Node boxes: a leaf's holds every point of its triangles within its cell (checked on the
  // triangles' vertices inside the cell and on their boxes clipped to the cell); a parent's
  // holds its children's.
  for (std::size_t i = 0; i < t.nodes.size(); ++i) {
    const Node& nd = t.nodes[i];
    const BlockBox& b = t.node_box[i];
    if (nd.kind == NodeKind::leaf) {
      const Leaf& lf = t.leaves[nd.index];
      Vec3d lo, hi;
      t.cell_box(nd.code, &lo, &hi);
      for (std::uint32_t k = 0; k < lf.tri_count; ++k) {
        const LeafTri& r = t.tris[lf.tri_begin + k];
        for (int a = 0; a < 3; ++a) {
          const double tlo = std::min({double(r.a[a]), double(r.b[a]), double(r.c[a])}),
                       thi = std::max({double(r.a[a]), double(r.b[a]), double(r.c[a])});
          const double clo = std::max(tlo, lo[a]), chi = std::min(thi, hi[a]);
          if (clo > chi) continue;  // listed within the margin only
          ASSERT_LE(double(b.lo[a]), clo) << i;
          ASSERT_GE(double(b.hi[a]), chi) << i;
        }
      }
    } else if (nd.kind == NodeKind::inner) {
      for (int o = 0; o < 8; ++o) {
        const std::uint32_t c = t.children[nd.index + o];
        if (t.nodes[c].kind != NodeKind::inner && t.nodes[c].kind != NodeKind::leaf) continue;
        for (int a = 0; a < 3; ++a) {
          ASSERT_LE(b.lo[a], t.node_box[c].lo[a]);
          ASSERT_GE(b.hi[a], t.node_box[c].hi[a]);
        }
      }
    }
  }
}
