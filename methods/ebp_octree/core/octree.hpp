#pragma once
/// The EBP-Octree (Extended Bounding-Planes Octree; Aguilera, Melero, Feito, CAD 77, 2016):
/// an octree over the model's bounding cube whose nodes are bounded by a subset of planes parallel
/// to the model's faces, with white (outside) / black (inside) empty nodes and per-leaf
/// configurations. See DESIGN.md beside this file for what is the paper's and what is ours.
///
/// This header is the in-memory structure (its builder: build/octree_build.cpp; its queries:
/// query.hpp). It depends on nothing of the harness but geometry.hpp, so that an out-of-core
/// store can reuse it.
///
/// The frame: every coordinate the structure holds (root_lo, cells, planes, leaf centres and
/// reference points, LeafTri vertices) is relative to `origin`, a point chosen at build from the
/// model's bounds (choose_origin, build_parts.hpp): 0 for a model near the origin, otherwise a
/// coarse point near the model's centre, so that float coordinates keep the model's own precision
/// however far it lies (a model 1e6 from the origin keeps ~1e-7 of its size, not 1/16 unit).
/// Query (query.hpp) takes and answers points in this frame; the harness adapters (ebp_method.cpp)
/// and OutOfCore translate the query point once, in double, and the closest point back.
///
/// Layout (all plain data, indices instead of pointers, so that the arrays can be written to a
/// file and mapped back as they are):
///   nodes    : every node, sorted by octcode = pre-order; a subtree is a contiguous range
///              [i, nodes[i].next).
///   children : 8 node indices per inner node (octant order x | y<<1 | z<<2).
///   planes   : the plane pool; a node's bounding planes are planes[plane_begin, +plane_count),
///              n.(x - root_centre) <= d, n unit (float), d rounded up so containment survives.
///   leaves   : one record per grey leaf (reference point and its colour, triangle block).
///   tris     : per-leaf triangle blocks, 48 bytes per reference: inline float coordinates, the
///              face plane in the leaf's frame (octahedral normal, offset) and the input
///              triangle index with the reference's flags.
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <utility>
#include <string>
#include <vector>

#include "harness/core/geometry.hpp"
#include "methods/ebp_octree/core/build_params.hpp"
#include "methods/ebp_octree/core/octcode.hpp"
#include "methods/ebp_octree/core/stats.hpp"

namespace ebp {

using bvhbench::Box3d;
using bvhbench::Vec3d;
using bvhbench::Vec3f;

enum class NodeKind : std::uint8_t { white = 0, black = 1, inner = 2, leaf = 3 };
enum class LeafConfig : std::uint8_t { convex = 0, concave = 1, special = 2 };
const char* to_string(NodeKind k);
const char* to_string(LeafConfig c);

struct Node {
  Octcode code;               ///< octcode (level in the low 5 bits)
  std::uint32_t plane_begin;  ///< first bounding plane in the pool
  std::uint16_t plane_count;  ///< number of bounding planes (the cell box bounds it too)
  NodeKind kind;
  LeafConfig config;          ///< leaves only
  std::uint32_t index;        ///< inner: first of 8 entries in `children`; leaf: index in `leaves`
  std::uint32_t next;         ///< one past the last node of this subtree (pre-order skip)
};
static_assert(sizeof(Node) == 24, "Node is 24 bytes of plain data");

struct Plane {
  float n[3];  ///< unit outward normal
  float d;     ///< offset, in the root's frame (x - root_centre): n.x <= d holds on the volume
};
static_assert(sizeof(Plane) == 16, "Plane is 16 bytes");

/// The flags of a LeafTri, in the top bits of LeafTri::tri_flags (the input index in the rest).
inline constexpr std::uint32_t kRefPositive = 1u << 31;  ///< the leaf's reference point is on the outer side
inline constexpr std::uint32_t kDegenerate = 1u << 30;   ///< zero area (exactly collinear): no parity role
inline constexpr std::uint32_t kNoPlane = 1u << 29;      ///< no face plane (degenerate or sliver): its value is 0
inline constexpr std::uint32_t kTriIndexMask = kNoPlane - 1;
/// The most input triangles a tree can index (the index shares its word with the flags).
inline constexpr std::uint64_t kMaxTriangles = std::uint64_t(kTriIndexMask) + 1;

/// One triangle reference in a leaf block, 48 bytes. Coordinates are the input's in the tree's
/// frame (input - origin, in double), rounded to float (the structure's geometry); all exact
/// predicates run on exactly these values. The face plane is a filter only: its normal is an
/// octahedral code (face_normal.hpp) and d its offset for the decoded normal v, so that the face
/// plane value v.(p - leaf centre) - d has the sign of orient3d(a, b, c, p) wherever its
/// magnitude exceeds the leaf's eps.
struct LeafTri {
  float a[3], b[3], c[3];
  std::uint32_t normal;     ///< octahedral code of the unit face normal (decode_face_normal)
  float d;                  ///< face plane v.(x - leaf centre) = d, v the decoded normal
  std::uint32_t tri_flags;  ///< index of the triangle in the input mesh | kRefPositive | kDegenerate | kNoPlane
  std::uint32_t tri() const { return tri_flags & kTriIndexMask; }
  std::uint32_t flags() const { return tri_flags & ~kTriIndexMask; }
  void set_tri(std::uint32_t t) { tri_flags = flags() | t; }
};
static_assert(sizeof(LeafTri) == 48, "LeafTri is 48 bytes");

struct Leaf {
  float centre[3];           ///< cell centre (float; the frame of the LeafTri planes)
  float ref[3];              ///< reference point, strictly inside the cell, off every face plane
  float eps;                 ///< bound on the float error of LeafTri plane evaluations in this leaf
  std::uint32_t tri_begin;   ///< first LeafTri
  std::uint32_t tri_count;
  std::int16_t ref_winding;  ///< winding number of the reference point (inside iff >= 1)
  std::uint8_t ref_valid;    ///< 0 if no reference point off every plane was found
  std::uint8_t pad;
};
static_assert(sizeof(Leaf) == 40, "Leaf is 40 bytes");

/// A float axis-aligned box (derived data, leaf_blocks.hpp): of a block of kBlockTris consecutive
/// LeafTris of a leaf, of a group of kGroupBlocks consecutive blocks, or of a node's geometry
/// within its cell.
struct BlockBox {
  float lo[3], hi[3];
  /// Whether it meets the closed box [qlo, qhi].
  bool meets(const float qlo[3], const float qhi[3]) const {
    return !(hi[0] < qlo[0] || lo[0] > qhi[0] || hi[1] < qlo[1] || lo[1] > qhi[1] || hi[2] < qlo[2] || lo[2] > qhi[2]);
  }
};
static_assert(sizeof(BlockBox) == 24, "BlockBox is 24 bytes");
inline constexpr std::uint32_t kBlockTris = 8;
/// The blocks of `tri_count` consecutive LeafTris (the last one partial).
constexpr std::uint32_t block_count(std::uint32_t tri_count) { return (tri_count + kBlockTris - 1) / kBlockTris; }
/// Blocks per group: a leaf of more than kGroupBlocks blocks has a box per group of kGroupBlocks
/// consecutive blocks (the layer above its blocks, leaf_blocks.hpp).
inline constexpr std::uint32_t kGroupBlocks = 8;
/// The groups of `blocks` consecutive blocks (the last one partial).
constexpr std::uint32_t group_count(std::uint32_t blocks) { return (blocks + kGroupBlocks - 1) / kGroupBlocks; }

/// A derived reference point of a leaf's octant (sub_references.hpp): strictly inside the
/// octant, off every face plane of the leaf, with its exact winding number.
struct SubRef {
  float p[3];
  std::int16_t winding;
  std::uint8_t valid;  ///< 0: none found (the leaf's own reference point serves the octant)
  std::uint8_t pad;
};
static_assert(sizeof(SubRef) == 16, "SubRef is 16 bytes");

class Octree {
 public:
  // --- the structure (read-only after build) ---
  /// The frame origin (world = frame + origin); every other coordinate here is in the frame.
  Vec3d origin{0, 0, 0};
  Vec3d to_frame(const Vec3d& world) const { return world - origin; }
  Vec3d to_world(const Vec3d& frame) const { return frame + origin; }
  Vec3d root_lo, root_centre;
  double root_size = 0;  ///< edge of the root cube
  int leaf_level = 0;
  std::uint32_t num_triangles = 0;  ///< in the input mesh
  /// Every undirected edge (by vertex index) is used equally often in both directions: the winding
  /// number is then path-independent, which coherent inside queries rely on (false: they don't).
  bool closed = false;
  std::vector<Node> nodes;
  std::vector<std::uint32_t> children;
  std::vector<Plane> planes;
  std::vector<Leaf> leaves;
  std::vector<LeafTri> tris;
  Stats stats;
  // --- derived from the above (leaf_blocks.cpp), by build and by every decoder; not stored ---
  std::vector<BlockBox> blocks;           ///< box of each group of kBlockTris LeafTris of a leaf
  std::vector<std::uint32_t> leaf_block;  ///< per leaf: its first block (ceil(tri_count / 8) blocks)
  std::vector<BlockBox> node_box;         ///< per node: box of its triangles within its cell
  std::vector<BlockBox> groups;           ///< box of each group of kGroupBlocks blocks of a leaf of more blocks
  std::vector<std::uint32_t> leaf_group;  ///< per leaf: its first group (none for a leaf of kGroupBlocks blocks or fewer)
  // --- derived (sub_references.cpp), on closed meshes only: empty otherwise ---
  std::vector<SubRef> sub_refs;           ///< per leaf, 8 in octant order
  std::vector<std::uint8_t> sub_sides;    ///< per block, 8 masks in octant order: bit j = LeafTri j of the block has sub-reference o on its outer side
  // --- derived (face_sides.cpp), on closed meshes only: empty otherwise ---
  std::vector<std::uint64_t> front_outside;  ///< bit per input triangle: its front is outside, its back inside
  std::size_t derived_bytes() const {
    return blocks.capacity() * sizeof(BlockBox) + leaf_block.capacity() * 4 + node_box.capacity() * sizeof(BlockBox) +
           groups.capacity() * sizeof(BlockBox) + leaf_group.capacity() * 4 +
           sub_refs.capacity() * sizeof(SubRef) + sub_sides.capacity() + front_outside.capacity() * 8;
  }
  /// The exact corner of a leaf's cell (its float centre is within rounding of the cell's).
  Vec3d leaf_corner(const Leaf& lf) const;

  std::size_t bytes() const;
  double cell_size(int level) const { return root_size / double(std::uint64_t(1) << level); }
  /// The cell box of a code.
  void cell_box(Octcode c, Vec3d* lo, Vec3d* hi) const;
  /// Index of the node whose cell holds leaf-grid cell (x, y, z) (a leaf or an empty node),
  /// found down from node `from` (the root, or any ancestor of the cell) by the cell's bits.
  std::uint32_t locate_cell(std::uint32_t x, std::uint32_t y, std::uint32_t z, std::uint32_t from = 0) const;
  /// The leaf-grid cells [r0, r1] (per axis) whose union holds the closed box [lo, hi], checked
  /// exactly against the cell boundaries; false if that takes more than 2 cells on an axis or the
  /// box leaves the root cube.
  bool leaf_cells_holding(const Vec3d& lo, const Vec3d& hi, std::uint32_t r0[3], std::uint32_t r1[3]) const;
};

// Cell geometry in double, as the searches walk it (the cell boundaries are exact doubles, "The
// frame" in DESIGN.md, so these are exact): a cube's corner `lo`, its children's edge `half`.

/// The octant (x | y << 1 | z << 2, the `children` order) of the child whose cell holds p (a
/// point on a boundary goes to the upper side).
inline int child_octant(const Vec3d& p, const Vec3d& lo, double half) {
  return (p.x >= lo.x + half ? 1 : 0) | (p.y >= lo.y + half ? 2 : 0) | (p.z >= lo.z + half ? 4 : 0);
}
/// The corner of child octant o.
inline Vec3d child_corner(const Vec3d& lo, double half, int o) {
  return {lo.x + ((o & 1) ? half : 0.0), lo.y + ((o & 2) ? half : 0.0), lo.z + ((o & 4) ? half : 0.0)};
}
/// The octant of a leaf's cell that holds p (x | y << 1 | z << 2, by the leaf's float centre:
/// the sub-references' order).
inline int leaf_octant(const Leaf& lf, const Vec3d& p) {
  return (p.x >= double(lf.centre[0]) ? 1 : 0) | (p.y >= double(lf.centre[1]) ? 2 : 0) |
         (p.z >= double(lf.centre[2]) ? 4 : 0);
}
/// Whether the closed cube [lo, lo + size] holds p.
inline bool cell_contains(const Vec3d& lo, double size, const Vec3d& p) {
  return p.x >= lo.x && p.y >= lo.y && p.z >= lo.z && p.x <= lo.x + size && p.y <= lo.y + size && p.z <= lo.z + size;
}
/// The squared distance from p to the cube [lo, lo + size] (0 inside).
inline double cell_d2(const Vec3d& lo, double size, const Vec3d& p) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double v = std::max({lo[k] - p[k], 0.0, p[k] - (lo[k] + size)});
    d2 += v * v;
  }
  return d2;
}

}  // namespace ebp
