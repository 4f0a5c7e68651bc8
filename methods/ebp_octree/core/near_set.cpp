// The near set of a coherent path (near_set.hpp): its gathering over the leaf-grid cells its box
// meets, and the outward float rounding of its box.
#include "methods/ebp_octree/core/near_set.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "methods/ebp_octree/core/leaf_kernels.hpp"

namespace ebp {

namespace {

/// The input triangles a gathering has kept that may be listed in two of its cells (a triangle
/// across a seam between them is kept once): an open-addressed set of input indices, at most
/// max_members + 1 entries in at least 2 max_members slots (never full), emptied on first use
/// (most gatherings keep no triangle across a seam, or span one cell).
class SeenTriangles {
 public:
  explicit SeenTriangles(std::uint32_t max_members)
      : bits_(max_members <= kNearMax / 2 ? kSlotBits - 1 : kSlotBits), mask_((1u << bits_) - 1) {}
  /// Adds `tri`; false if it was there already.
  bool insert(std::uint32_t tri) {
    if (!emptied_) {
      if (bits_ == kSlotBits)  // (two constant sizes: the compiler writes each inline)
        std::fill(slots_, slots_ + kSlots, UINT32_MAX);
      else
        std::fill(slots_, slots_ + kSlots / 2, UINT32_MAX);
      emptied_ = true;
    }
    std::uint32_t h = (tri * 0x9E3779B1u) >> (32 - bits_);  // Fibonacci hashing
    for (; slots_[h] != UINT32_MAX; h = (h + 1) & mask_)
      if (slots_[h] == tri) return false;
    slots_[h] = tri;
    return true;
  }

 private:
  static constexpr std::uint32_t kSlots = 2 * kNearMax;
  static constexpr int kSlotBits = __builtin_ctz(kSlots);
  static_assert((kSlots & (kSlots - 1)) == 0, "a power of two: the hash's top bits index the slots");
  int bits_;
  std::uint32_t mask_;
  bool emptied_ = false;
  std::uint32_t slots_[kSlots];
};

/// The seam slabs of a gathering over the cells [r0, r1] (GatherTest): on an axis where it spans
/// two cells, the boundary between them widened by more than the distribution's margins, rounded
/// outwards to float; empty on the other axes. The distribution lists a triangle in a leaf cell
/// only when its box comes within 1e-6 of a cell's size plus 2e-9 of its own extent of the cell,
/// or within 1e-9 of the root's size in the separating-axis test (build/frame.cpp,
/// build/tri_box.hpp); a triangle listed in cells on both sides of a seam therefore has a box
/// that meets the slab.
void seam_slabs(const Octree& t, const std::uint32_t r0[3], const std::uint32_t r1[3], GatherTest& g) {
  const double cs = t.cell_size(t.leaf_level), margin = 4e-6 * cs + 1e-8 * t.root_size;
  for (int a = 0; a < 3; ++a) {
    if (r0[a] == r1[a]) {
      g.seam_lo[a] = std::numeric_limits<float>::infinity();
      g.seam_hi[a] = -std::numeric_limits<float>::infinity();
      continue;
    }
    const double seam = t.root_lo[a] + double(r1[a]) * cs;
    g.seam_lo[a] = float_down(seam - margin);
    g.seam_hi[a] = float_up(seam + margin);
  }
}

}  // namespace

bool NearSet::gather(const Octree& t, const Vec3d& glo, const Vec3d& ghi, std::uint32_t leaf_node,
                     bool with_degenerate, std::uint32_t max_members) {
  max_members = std::min(max_members, kNearMax);
  valid = false;
  overflowed = false;
  n = 0;
  const int L = t.leaf_level;
  GatherTest test;
  for (int a = 0; a < 3; ++a) {
    test.lo[a] = lo[a] = float_down(glo[a]);
    test.hi[a] = hi[a] = float_up(ghi[a]);
  }
  test.with_degenerate = with_degenerate;
  std::uint32_t r0[3], r1[3];
  if (!t.leaf_cells_holding(Vec3d(lo[0], lo[1], lo[2]), Vec3d(hi[0], hi[1], hi[2]), r0, r1)) return false;
  seam_slabs(t, r0, r1, test);
  const bool several = r0[0] != r1[0] || r0[1] != r1[1] || r0[2] != r1[2];
  const LeafTri* tris = t.tris.data();
  const LeafKernelTable& K = leaf_kernel_table();
  const MemberColumns columns{{blo[0], blo[1], blo[2]}, {bhi[0], bhi[1], bhi[2]}, k, leaf, node, kNearMax};
  SeenTriangles seen(max_members);
  for (std::uint32_t z = r0[2]; z <= r1[2]; ++z)
    for (std::uint32_t y = r0[1]; y <= r1[1]; ++y)
      for (std::uint32_t x = r0[0]; x <= r1[0]; ++x) {
        const std::uint32_t ni = (several || leaf_node == UINT32_MAX) ? t.locate_cell(x, y, z) : leaf_node;
        const Node& nd = t.nodes[ni];
        if (nd.kind != NodeKind::leaf) {
          if (!octcode_contains(nd.code, octcode_from_cell(L, x, y, z))) return false;
          continue;  // an empty node: no triangle meets its closed cell
        }
        const Leaf& lf = t.leaves[nd.index];
        const BlockBox* block_boxes = t.blocks.data() + t.leaf_block[nd.index];
        const std::uint32_t nb = block_count(lf.tri_count);
        static_assert(kGroupBlocks == 8, "a group's blocks are one pass of the block kernel");
        const BlockBox* group_boxes = t.leaf_group.empty() ? nullptr : t.groups.data() + t.leaf_group[nd.index];
        for (std::uint32_t b0 = 0; b0 < nb; b0 += 8) {
          if (group_boxes && nb > kGroupBlocks && !group_boxes[b0 / kGroupBlocks].meets(lo, hi))
            continue;  // the group's box first
          for (unsigned bh = K.block_pass(block_boxes + b0, std::min(nb - b0, 8u), lo, hi); bh; bh &= bh - 1) {
            const std::uint32_t first_in_leaf = (b0 + unsigned(__builtin_ctz(bh))) * kBlockTris;
            const std::uint32_t first = lf.tri_begin + first_in_leaf;
            BlockTriBoxes boxes;
            unsigned on_seam;
            unsigned keep =
                K.box_pass(tris + first, std::min(lf.tri_count - first_in_leaf, kBlockTris), test, boxes, &on_seam);
            for (; on_seam; on_seam &= on_seam - 1) {  // kept from the first of its cells only
              const unsigned j = unsigned(__builtin_ctz(on_seam));
              if (!seen.insert(tris[first + j].tri())) keep &= ~(1u << j);
            }
            if (!keep) continue;
            n += K.append_members(boxes, keep, first, nd.index, ni, columns, n);
            if (n > max_members) {
              overflowed = true;
              n = 0;
              return false;
            }
          }
        }
      }
  for (std::uint32_t j = n; j % 8 != 0; ++j)  // padding: empty boxes
    for (int a = 0; a < 3; ++a) {
      blo[a][j] = std::numeric_limits<float>::infinity();
      bhi[a][j] = -std::numeric_limits<float>::infinity();
    }
  valid = true;
  return true;
}

std::uint32_t NearSet::within(const float q_lo[3], const float q_hi[3], float box_lim, float g2[kNearMax],
                              std::uint64_t mask[kNearMaskWords]) const {
  const std::uint32_t words = (n + 63) / 64;
  for (std::uint32_t w = 0; w < words; ++w) {
    const std::uint32_t first = 64 * w, count = std::min<std::uint32_t>(64, n - first);
    const float* const lo[3] = {blo[0] + first, blo[1] + first, blo[2] + first};
    const float* const hi[3] = {bhi[0] + first, bhi[1] + first, bhi[2] + first};
    mask[w] = leaf_kernel_table().column_box_pass(lo, hi, count, q_lo, q_hi, box_lim, g2 + first);
  }
  return words;
}

}  // namespace ebp
