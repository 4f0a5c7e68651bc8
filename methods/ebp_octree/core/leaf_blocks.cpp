// Leaf blocks: spatial order of the leaf triangle blocks and the derived float boxes (blocks of
// kBlockTris triangles, nodes). Every box contains exactly what it claims (the float vertices are
// exact doubles; min/max are exact; cell bounds are rounded outward to float), so any distance to
// a box, with the query's rounding tolerance, is a lower bound and pruning by it is exact.
#include "methods/ebp_octree/core/leaf_blocks.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace ebp {

namespace {

struct Cent {
  double c[3];
  std::uint32_t tri;
  std::uint32_t k;  // position in the input block
};

void split(Cent* c, std::uint32_t n) {
  if (n <= 1) return;
  double lo[3], hi[3];
  for (int a = 0; a < 3; ++a) lo[a] = hi[a] = c[0].c[a];
  for (std::uint32_t i = 1; i < n; ++i)
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], c[i].c[a]);
      hi[a] = std::max(hi[a], c[i].c[a]);
    }
  int ax = 0;
  for (int a = 1; a < 3; ++a)
    if (hi[a] - lo[a] > hi[ax] - lo[ax]) ax = a;
  std::sort(c, c + n, [ax](const Cent& x, const Cent& y) {
    return x.c[ax] < y.c[ax] || (x.c[ax] == y.c[ax] && x.tri < y.tri);
  });
  if (n <= kBlockTris) return;  // one block, itself in order along its widest axis
  // Split point: half, rounded up to a multiple of kBlockTris (so every block but the last of
  // the leaf is full and stays within one side), and of a group's triangles while the part holds
  // more than a group (so that each group of kGroupBlocks consecutive blocks is compact too).
  const std::uint32_t unit = n > kGroupBlocks * kBlockTris ? kGroupBlocks * kBlockTris : kBlockTris;
  std::uint32_t m = (n / 2 + unit - 1) / unit * unit;
  if (m >= n) m = block_count(n / 2) * kBlockTris;
  if (m >= n) m = n - (n % kBlockTris ? n % kBlockTris : kBlockTris);
  split(c, m);
  split(c + m, n - m);
}

inline float down(double x) {
  float f = float(x);
  if (double(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}
inline float up(double x) {
  float f = float(x);
  if (double(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

BlockBox empty_box() {
  BlockBox b;
  for (int a = 0; a < 3; ++a) {
    b.lo[a] = std::numeric_limits<float>::infinity();
    b.hi[a] = -std::numeric_limits<float>::infinity();
  }
  return b;
}

void grow(BlockBox& b, const BlockBox& x) {
  for (int a = 0; a < 3; ++a) {
    b.lo[a] = std::min(b.lo[a], x.lo[a]);
    b.hi[a] = std::max(b.hi[a], x.hi[a]);
  }
}

}  // namespace

void order_leaf_triangles(LeafTri* block, std::uint32_t n) {
  if (n <= 1) return;
  std::vector<Cent> c(n);
  for (std::uint32_t k = 0; k < n; ++k) {
    const LeafTri& t = block[k];
    for (int a = 0; a < 3; ++a) c[k].c[a] = double(t.a[a]) + double(t.b[a]) + double(t.c[a]);
    c[k].tri = t.tri();
    c[k].k = k;
  }
  split(c.data(), n);
  std::vector<LeafTri> tmp(block, block + n);
  for (std::uint32_t k = 0; k < n; ++k) block[k] = tmp[c[k].k];
}

void compute_leaf_blocks(Octree& T, bool with_groups) {
  T.leaf_block.assign(T.leaves.size(), 0);
  std::size_t nb = 0;
  for (std::size_t li = 0; li < T.leaves.size(); ++li) {
    if (nb > 0xffffffffull) throw std::length_error("too many leaf blocks");
    T.leaf_block[li] = std::uint32_t(nb);
    nb += block_count(T.leaves[li].tri_count);
  }
  T.blocks.assign(nb, empty_box());
  for (std::size_t li = 0; li < T.leaves.size(); ++li) {
    const Leaf& lf = T.leaves[li];
    for (std::uint32_t k = 0; k < lf.tri_count; ++k) {
      const LeafTri& t = T.tris[std::size_t(lf.tri_begin) + k];
      BlockBox& b = T.blocks[T.leaf_block[li] + k / kBlockTris];
      for (int a = 0; a < 3; ++a) {
        b.lo[a] = std::min({b.lo[a], t.a[a], t.b[a], t.c[a]});
        b.hi[a] = std::max({b.hi[a], t.a[a], t.b[a], t.c[a]});
      }
    }
  }
  // Group boxes: the union of their blocks' boxes, for leaves of more than kGroupBlocks blocks.
  T.leaf_group.assign(with_groups ? T.leaves.size() : 0, 0);
  std::size_t ng = 0;
  for (std::size_t li = 0; li < T.leaf_group.size(); ++li) {
    const std::uint32_t nb = block_count(T.leaves[li].tri_count);
    T.leaf_group[li] = std::uint32_t(ng);
    if (nb > kGroupBlocks) ng += group_count(nb);
  }
  T.groups.assign(ng, empty_box());
  for (std::size_t li = 0; li < T.leaf_group.size(); ++li) {
    const std::uint32_t nb = block_count(T.leaves[li].tri_count);
    if (nb <= kGroupBlocks) continue;
    for (std::uint32_t j = 0; j < nb; ++j) grow(T.groups[T.leaf_group[li] + j / kGroupBlocks], T.blocks[T.leaf_block[li] + j]);
  }
  // Node boxes, children before parents (children have larger indices in every Octree we make:
  // pre-order in build and load_all, checked by the page decoder). Leaves: the union of their
  // blocks clipped to the cell (the geometry a leaf stands for is its triangles within its cell;
  // an empty intersection gives an inverted box, whose distance is still a lower bound of the
  // distance to nothing). White/black nodes: empty.
  T.node_box.assign(T.nodes.size(), empty_box());
  for (std::size_t i = T.nodes.size(); i-- > 0;) {
    const Node& nd = T.nodes[i];
    BlockBox& b = T.node_box[i];
    if (nd.kind == NodeKind::leaf) {
      const Leaf& lf = T.leaves[nd.index];
      const std::uint32_t n = block_count(lf.tri_count);
      for (std::uint32_t j = 0; j < n; ++j) grow(b, T.blocks[T.leaf_block[nd.index] + j]);
      Vec3d lo, hi;
      T.cell_box(nd.code, &lo, &hi);
      for (int a = 0; a < 3; ++a) {
        b.lo[a] = std::max(b.lo[a], down(lo[a]));
        b.hi[a] = std::min(b.hi[a], up(hi[a]));
      }
    } else if (nd.kind == NodeKind::inner) {
      for (std::uint32_t o = 0; o < 8; ++o) {
        const std::uint32_t c = T.children[std::size_t(nd.index) + o];
        if (c <= i || c >= T.nodes.size()) {  // not our layout: no box (the cell box bounds it)
          b.lo[0] = b.lo[1] = b.lo[2] = -std::numeric_limits<float>::infinity();
          b.hi[0] = b.hi[1] = b.hi[2] = std::numeric_limits<float>::infinity();
          break;
        }
        grow(b, T.node_box[c]);
      }
    }
  }
}

bool has_leaf_blocks(const Octree& T) {
  return T.leaf_block.size() == T.leaves.size() && (T.leaf_group.empty() || T.leaf_group.size() == T.leaves.size()) &&
         T.node_box.size() == T.nodes.size();
}

}  // namespace ebp
