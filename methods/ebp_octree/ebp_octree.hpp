#pragma once
/// The EBP-Octree (Extended Bounding-Planes Octree; Aguilera, Melero, Feito, CAD 77, 2016):
/// an octree over the model's bounding cube whose nodes are bounded by a subset of planes parallel
/// to the model's faces, with white (outside) / black (inside) empty nodes and per-leaf
/// configurations. See DESIGN.md beside this file for what is the paper's and what is ours.
///
/// This header is the in-memory structure, its builder and its queries. It depends on nothing of
/// the harness but geometry.hpp, so that an out-of-core store can reuse it.
///
/// Layout (all plain data, indices instead of pointers, so that the arrays can be written to a
/// file and mapped back as they are):
///   nodes    : every node, sorted by octcode = pre-order; a subtree is a contiguous range
///              [i, nodes[i].next).
///   children : 8 node indices per inner node (octant order x | y<<1 | z<<2).
///   planes   : the plane pool; a node's bounding planes are planes[plane_begin, +plane_count),
///              n.(x - root_centre) <= d, n unit (float), d rounded up so containment survives.
///   leaves   : one record per grey leaf (reference point and its colour, triangle block).
///   tris     : per-leaf triangle blocks, 64 bytes (one cache line) per reference: inline float
///              coordinates, the face plane in the leaf's frame and the input triangle index.
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <utility>
#include <string>
#include <vector>

#include "harness/core/geometry.hpp"
#include "octcode.hpp"

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

/// One triangle reference in a leaf block. Coordinates are the input's, rounded to float (the
/// structure's geometry); all exact predicates run on exactly these values.
struct LeafTri {
  float a[3], b[3], c[3];
  float n[3];    ///< unit face normal (float); zero for slivers whose normal is ill-conditioned
  float d;       ///< face plane n.(x - leaf centre) = d
  std::uint32_t tri;    ///< index of the triangle in the input mesh
  std::uint32_t flags;  ///< kRefPositive | kDegenerate
  float pad;
};
static_assert(sizeof(LeafTri) == 64, "LeafTri is one cache line");
inline constexpr std::uint32_t kRefPositive = 1;  ///< the leaf's reference point is on the outer side
inline constexpr std::uint32_t kDegenerate = 2;   ///< zero area (exactly collinear): no parity role

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

/// A float axis-aligned box (derived data, leaf_blocks.hpp): of a group of kBlockTris consecutive
/// LeafTris of a leaf, or of a node's geometry within its cell.
struct BlockBox {
  float lo[3], hi[3];
};
static_assert(sizeof(BlockBox) == 24, "BlockBox is 24 bytes");
inline constexpr std::uint32_t kBlockTris = 8;

struct BuildParams {
  double leaf_factor = 5.0;     ///< leaf cell size >= leaf_factor x average edge length
  int max_planes = 8;           ///< bounding planes per node (at most)
  double cluster_angle = 30.0;  ///< degrees: normals closer than this share one plane
  int threads = 1;              ///< > 1: TBB parallel build
  int max_level = kMaxLevel;    ///< clamp of the leaf level (1..19)
};

/// Figures researchers cite (`bvhbench ebp stats`).
struct Stats {
  int leaf_level = 0;
  double root_size = 0, leaf_size = 0, average_edge = 0;
  std::size_t triangles = 0, nodes = 0, inner = 0, leaves = 0, white = 0, black = 0;
  std::size_t convex = 0, concave = 0, special = 0;
  std::size_t triangle_refs = 0, max_refs_per_leaf = 0;
  std::size_t planes = 0, max_planes_per_node = 0;
  std::size_t leaf_planes = 0, inner_planes = 0;
  double leaf_box_volume = 0, leaf_volume = 0;    ///< sum over grey leaves: cell boxes, bounding volumes
  double inner_box_volume = 0, inner_volume = 0;  ///< sum over grey inner nodes
  std::size_t colour_fallbacks = 0;   ///< components coloured by the winding number (see DESIGN.md)
  std::size_t degenerate_edges = 0;   ///< colouring edges skipped (segment through an edge/vertex)
  std::size_t invalid_refs = 0;       ///< leaves without a reference point off every plane
  std::vector<std::size_t> nodes_per_level;
  double build_seconds = 0;
  double seconds_distribute = 0, seconds_leaves = 0, seconds_inner = 0, seconds_colour = 0;
};

class Octree {
 public:
  /// Builds over `vertices` (#V) and `triangles` (#F, indices into vertices). Triangles may be
  /// degenerate or repeated; #F >= 1. Throws std::invalid_argument on an index out of range or a
  /// non-finite coordinate. `progress` (optional) receives fractions in [0, 1].
  static Octree build(const std::vector<Vec3d>& vertices,
                      const std::vector<std::array<std::uint32_t, 3>>& triangles,
                      const BuildParams& params,
                      const std::function<void(double)>& progress = nullptr);

  // --- the structure (read-only after build) ---
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
  std::size_t derived_bytes() const {
    return blocks.capacity() * sizeof(BlockBox) + leaf_block.capacity() * 4 + node_box.capacity() * sizeof(BlockBox);
  }

  std::size_t bytes() const;
  double cell_size(int level) const { return root_size / double(std::uint64_t(1) << level); }
  /// The cell box of a code.
  void cell_box(Octcode c, Vec3d* lo, Vec3d* hi) const;
  /// Index of the node whose cell holds leaf-grid cell (x, y, z) (a leaf or an empty node).
  std::uint32_t locate_cell(std::uint32_t x, std::uint32_t y, std::uint32_t z) const;
};

/// Work counters of the queries (deterministic).
struct QueryCounters {
  std::uint64_t nodes_visited = 0, planes_tested = 0, triangles_tested = 0;
  std::uint64_t hit_white = 0, hit_black = 0, hit_convex = 0, hit_concave = 0, hit_special = 0;
  std::uint64_t exact_fallbacks = 0;  ///< parity retried with another reference point
};

struct DistanceAnswer {
  double distance = 0;  ///< signed, negative inside
  Vec3d closest, normal;
  std::int64_t triangle = -1;
};

/// The running best of a distance query, possibly over several trees (the out-of-core pages):
/// the lexicographic minimum of (squared distance, key), key = input triangle index.
struct DistanceBest {
  double best2 = std::numeric_limits<double>::infinity();
  double best = std::numeric_limits<double>::infinity();
  std::uint64_t key = UINT64_MAX;
  Vec3d closest;
  std::uint32_t k = UINT32_MAX;     ///< LeafTri index of the best, if the last call found it in its tree
  std::uint32_t leaf = UINT32_MAX;  ///< and the leaf it was found in
  std::uint32_t node = UINT32_MAX;  ///< and that leaf's node, if known
};

/// Where and how Query::distance_bound starts.
struct DistanceStart {
  const std::uint32_t* key_of = nullptr;  ///< LeafTri::tri -> key (increasing); null: key = tri
  std::uint32_t seed_tri = UINT32_MAX;    ///< a LeafTri index tested first (a valid upper bound)
  std::uint32_t seed_leaf = UINT32_MAX;   ///< a leaf scanned before the descent
  std::uint32_t seed_node = UINT32_MAX;   ///< its node, if known (its planes then bound the blocks)
  std::uint32_t node = 0;                 ///< the subtree searched (its whole geometry)
};

/// Query state over a built Octree: per-query stamps, the coherent path state, counters.
/// One per thread. No allocation per query.
class Query {
 public:
  Query(const Octree& tree, bool coherent);
  bool inside(const Vec3d& p);
  DistanceAnswer distance(const Vec3d& p);
  /// Unsigned distance only (no inside test); fills closest/normal/triangle.
  DistanceAnswer unsigned_distance(const Vec3d& p);
  /// Branch and bound over the subtree `s.node`, starting from the running best `b` (an upper
  /// bound, ties kept: only what is strictly worse than it is pruned). `b` becomes the minimum of
  /// itself and the subtree's triangles, by (squared distance, key); b.k / b.leaf are set if one
  /// of this tree's triangles is the new best, UINT32_MAX otherwise. With the initial bound
  /// >= the true distance, the answer is the one without it, bit for bit.
  void distance_bound(const Vec3d& p, DistanceBest& b, const DistanceStart& s);
  void reset_path();
  QueryCounters counters;

 private:
  std::uint32_t locate(const Vec3d& p, bool* outside_root);
  bool classify_leaf(const Vec3d& p, const Leaf& leaf, std::uint32_t leaf_index, std::uint32_t node);
  const Octree& t_;
  bool coherent_;
  std::vector<std::uint32_t> stamp_;
  std::uint32_t query_id_ = 0;
  // coherent inside (closed meshes): the last point of the path whose winding number is known
  // exactly (see classify_leaf and DESIGN.md), and the bounding boxes of the triangles of the
  // last few leaves used, as float arrays (a cache of derived data; answers do not depend on it).
  struct LeafBoxes {
    std::uint32_t leaf = UINT32_MAX;  ///< leaf index, or none
    std::uint32_t n4 = 0;             ///< slots: each octant group padded to 4 with empty boxes
    std::uint32_t group[9] = {};      ///< the slots of octant g are [group[g], group[g + 1])
    float glo[3][8], ghi[3][8];       ///< each group's bounding box
    std::vector<float> b;             ///< lo x[n4], lo y, lo z, hi x, hi y, hi z
    std::vector<std::uint32_t> k;     ///< the slot's triangle, offset in the leaf's block
  };
  bool step_from_prev(const Vec3d& p, std::uint32_t leaf_node, int* w);
  const LeafBoxes& leaf_boxes(std::uint32_t leaf_index);
  bool prev_ok_ = false;
  Vec3d prev_p_;
  int prev_w_ = 0;
  std::vector<LeafBoxes> leaf_boxes_;  // direct-mapped by leaf index
  std::vector<float> tmp_box_;
  // coherent state
  std::uint32_t last_node_ = UINT32_MAX;
  std::uint32_t last_cell_[3] = {0, 0, 0};
  int last_level_ = 0;
  std::uint32_t last_tri_ = UINT32_MAX;  // LeafTri index of the previous closest triangle
  std::uint32_t last_leaf_ = UINT32_MAX;  // and the leaf where it was found
  std::uint32_t last_leaf_node_ = UINT32_MAX;  // and that leaf's node
  // distance: leaves already scanned by this query, scratch for the block order
  std::vector<std::uint32_t> leaf_stamp_;
  std::vector<std::pair<double, std::uint32_t>> order_;
};

/// Winding-number change along segment p -> q over the (non-degenerate) triangles of `list`,
/// exactly: the sum over proper crossings of +1 (entering: from the side the normal points to, to
/// the other) or -1 (leaving), i.e. w(q) - w(p). Returns false (and leaves *delta alone) if the
/// segment passes through an edge or a vertex, lies in a triangle's plane over it, or an endpoint
/// lies on a triangle. Build-time helper, exposed for tests.
bool segment_winding(const Vec3d& p, const Vec3d& q, const LeafTri* const* list, std::size_t n, int* delta);
bool segment_winding(const Vec3d& p, const Vec3d& q, const LeafTri* list, std::size_t n, int* delta);

/// Fixed offsets, in fractions of the half cell from the cell centre, of the candidate reference
/// points of a leaf (the first near the centre, then a Halton sequence inside (-0.45, 0.45)^3).
const std::vector<Vec3d>& ref_offsets();

}  // namespace ebp
