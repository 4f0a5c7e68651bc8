// The query state over a built Octree (query.hpp): its construction, the path reset, and point
// location by octcode descent (with the coherent shortcut), which both queries start from. The
// queries: query_inside.cpp (exact point-in-solid), query_distance.cpp (branch and bound).
#include <algorithm>
#include <cstddef>
#include <stdexcept>

#include "methods/ebp_octree/core/leaf_blocks.hpp"
#include "methods/ebp_octree/core/query.hpp"

namespace ebp {

namespace {
constexpr std::size_t kLeafBoxSlots = 64;  // Query::leaf_boxes_ (at most)
}  // namespace

Query::Query(const Octree& tree, bool coherent)
    : t_(tree), coherent_(coherent), stamp_(tree.num_triangles, 0), leaf_stamp_(tree.leaves.size(), 0) {
  if (!has_leaf_blocks(t_)) throw std::logic_error("ebp::Query: the Octree lacks its leaf blocks (compute_leaf_blocks)");
  std::uint32_t mb = 0;
  for (const Leaf& lf : t_.leaves) mb = std::max(mb, (lf.tri_count + kBlockTris - 1) / kBlockTris);
  order_.resize(mb);
  if (coherent_ && t_.closed) {  // a power of two, no more than the leaves (an out-of-core page has few)
    std::size_t slots = 1;
    while (slots < kLeafBoxSlots && slots < t_.leaves.size()) slots *= 2;
    leaf_boxes_.resize(slots);
  }
}

void Query::reset_path() {
  last_node_ = UINT32_MAX;
  last_tri_ = UINT32_MAX;
  last_leaf_ = UINT32_MAX;
  last_leaf_node_ = UINT32_MAX;
  prev_ok_ = false;
}

std::uint32_t Query::locate(const Vec3d& p, bool* outside_root) {
  const double inv = double(std::uint64_t(1) << t_.leaf_level) / t_.root_size;
  const double G = double(std::uint64_t(1) << t_.leaf_level);
  const double rx = (p.x - t_.root_lo.x) * inv, ry = (p.y - t_.root_lo.y) * inv, rz = (p.z - t_.root_lo.z) * inv;
  if (!(rx >= 0 && ry >= 0 && rz >= 0 && rx <= G && ry <= G && rz <= G)) {
    *outside_root = true;
    return UINT32_MAX;
  }
  *outside_root = false;
  const std::uint32_t gmax = (1u << t_.leaf_level) - 1;
  const std::uint32_t x = std::min(std::uint32_t(rx), gmax), y = std::min(std::uint32_t(ry), gmax),
                      z = std::min(std::uint32_t(rz), gmax);
  if (coherent_ && last_node_ != UINT32_MAX) {
    const int sh = t_.leaf_level - last_level_;
    if ((x >> sh) == last_cell_[0] && (y >> sh) == last_cell_[1] && (z >> sh) == last_cell_[2]) {
      ++counters.nodes_visited;
      return last_node_;
    }
  }
  std::uint32_t i = 0;
  const Node* nodes = t_.nodes.data();
  const std::uint32_t* ch = t_.children.data();
  int level = 0;
  ++counters.nodes_visited;
  while (nodes[i].kind == NodeKind::inner) {
    const int shift = t_.leaf_level - level - 1;
    const std::uint32_t o = ((x >> shift) & 1u) | (((y >> shift) & 1u) << 1) | (((z >> shift) & 1u) << 2);
    i = ch[nodes[i].index + o];
    ++level;
    ++counters.nodes_visited;
  }
  if (coherent_) {
    last_node_ = i;
    last_level_ = level;
    const int sh = t_.leaf_level - level;
    last_cell_[0] = x >> sh;
    last_cell_[1] = y >> sh;
    last_cell_[2] = z >> sh;
  }
  return i;
}

}  // namespace ebp
