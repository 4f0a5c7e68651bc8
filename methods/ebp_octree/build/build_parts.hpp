#pragma once
/// The pieces of the EBP-Octree builder that the in-memory `build_octree` (octree_build.hpp) and the
/// external-memory build (external_build.cpp) share, so that both compute every node with the very
/// same code: the frame (root cube, leaf level), the distribution of one triangle to leaf cells,
/// one leaf (triangle block, planes, configuration, reference point, colouring half-edges), one
/// inner node (planes from its children's bounding volumes), and the colouring (union-find with
/// winding-number potentials over the node skeleton). Internal to the ebp_octree library.
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "methods/ebp_octree/core/octree.hpp"

namespace ebp::detail {

/// The frame origin of a build (Octree::origin) from the bounds of all the input's vertices (in
/// double, as read): each coordinate of the box centre rounded to a multiple of g, the power of two
/// >= 8 x the box's largest extent. So a model whose centre is within ~4 extents of the origin
/// gets origin 0 (its float geometry is the input rounded to float, as always), and a model far
/// out gets a coarse origin near its centre (float(v - origin) keeps ~2^-24 of 8 x its size); the
/// origin is a multiple of g, so v - origin is exact in double for every vertex. Both builds
/// (in memory and external) compute it from the same bounds: the same frame, the same bytes.
Vec3d choose_origin(const Box3d& vertex_bounds);

/// Bounding box and edge-length sum of the triangles, accumulated in input order (the edge sum is
/// a double sum whose order matters: both builds add triangle by triangle, in input order).
struct FrameAccumulator {
  Box3d bb;
  double edge_sum = 0;
  std::uint64_t triangles = 0;
  /// a, b, c: the triangle's vertices already rounded to float.
  void add(const Vec3d& a, const Vec3d& b, const Vec3d& c);
};

/// The frame every cell is computed in (Octree::root_lo, root_centre, root_size, leaf_level).
struct Frame {
  Vec3d root_lo, root_centre;
  double root_size = 0;
  int leaf_level = 0;
  double average_edge = 0;
  double cell_size(int level) const { return root_size / double(std::uint64_t(1) << level); }
  void cell_box(Octcode c, Vec3d* lo, Vec3d* hi) const;
};
Frame compute_frame(const FrameAccumulator& acc, const BuildParams& prm);

/// Build constants derived from the frame and the parameters.
struct BuildContext {
  Frame f;
  double cs = 0;        ///< leaf cell size
  std::uint32_t G = 0;  ///< leaf cells per axis
  double cos_cluster = 1;
  int max_planes = 8;
  double plane_margin = 0;
  BuildContext(const Frame& frame, const BuildParams& prm);
};

/// Appends the Morton codes of the leaf cells triangle (a, b, c) (float-rounded) touches.
void distribute_triangle(const BuildContext& ctx, const Vec3d& a, const Vec3d& b, const Vec3d& c,
                         std::vector<std::uint64_t>& out);

/// Temporary per-node build data: the node's planes and the vertices of its bounding volume.
struct NodeTmp {
  std::vector<Plane> planes;  // final (float) planes, root frame
  std::vector<Vec3d> poly;    // vertices of the bounding volume (world)
  double volume = 0, box_volume = 0;
};

/// Colouring half-edge of a leaf: the winding-number change from the leaf's reference point to
/// the portal of each of its 6 faces (colour() combines two halves into one adjacency), or
/// kDegenerateHalf if the segment passes through an edge/vertex (the adjacency is then skipped).
inline constexpr std::int32_t kDegenerateHalf = INT32_MIN;
struct LeafHalves {
  std::int32_t h[6];
};

/// Builds one grey leaf at `code` from its triangles, in increasing input index order: `tri[k]`
/// the input index, `xyz[9k..9k+8]` its float vertices a, b, c. Fills `nd` (kind leaf, config),
/// `lf` (everything but tri_begin, which the caller sets, and ref_winding, set by colour()),
/// `out[0..n)` (the LeafTri block), `tm` (planes and bounding volume) and `halves`.
void build_leaf(const BuildContext& ctx, Octcode code, std::size_t n, const std::uint32_t* tri, const float* xyz,
                Node* nd, Leaf* lf, LeafTri* out, NodeTmp* tm, LeafHalves* halves);

/// Builds one grey inner node at `code` from its children's temporaries (nullptr for empty
/// children); frees the children's polytopes.
void build_inner(const BuildContext& ctx, Octcode code, NodeTmp* const children[8], NodeTmp* tm);

/// Bytes of one node in a page (Node, its planes, its children block or leaf record + triangle
/// block + local triangle table entries): the page writer's measure of a subtree.
inline std::uint64_t node_page_bytes(NodeKind kind, std::uint32_t plane_count, std::uint32_t tri_count) {
  std::uint64_t b = sizeof(Node) + sizeof(Plane) * std::uint64_t(plane_count);
  if (kind == NodeKind::inner) b += 8 * sizeof(std::uint32_t);
  if (kind == NodeKind::leaf) b += sizeof(Leaf) + std::uint64_t(tri_count) * (sizeof(LeafTri) + sizeof(std::uint32_t));
  return b;
}

/// The node skeleton the colouring needs (all nodes, octcode order = pre-order).
struct Skeleton {
  int leaf_level = 0;
  std::vector<Octcode> code;
  std::vector<NodeKind> kind;         ///< white (empty, colour unknown), inner, leaf
  std::vector<std::uint32_t> index;   ///< inner: first child entry; leaf: leaf index
  std::vector<std::uint32_t> children;
  std::vector<std::uint32_t> leaf_node;  ///< per leaf: its node
  std::vector<std::array<float, 3>> leaf_ref;
  std::vector<std::uint8_t> leaf_ref_valid;
  std::vector<LeafHalves> leaf_halves;
  std::uint32_t locate_cell(std::uint32_t x, std::uint32_t y, std::uint32_t z) const;
  std::size_t bytes() const;
};

/// Result of the colouring: which empty nodes are black, the winding of each leaf's reference.
struct Colouring {
  std::vector<std::uint32_t> black;       ///< nodes (white in the skeleton) that are inside
  std::vector<std::int16_t> ref_winding;  ///< per leaf
  std::size_t colour_fallbacks = 0, degenerate_edges = 0, invalid_refs = 0;
};

/// Generalised winding numbers of points over the whole mesh (the fallback of components no
/// adjacency reached; rare): sum over triangles in input order of bvhbench::triangle_winding on
/// the float vertices, rounded.
using WindingBatch = std::function<std::vector<int>(const std::vector<Vec3d>& points)>;

Colouring colour(const Frame& f, Skeleton& sk, const WindingBatch& winding_at);

/// The portal of a leaf face: a fixed point strictly inside the face shared by the leaf-level
/// cells (x, y, z) and its neighbour across `dir` (axis dir >> 1, positive side if dir & 1).
Vec3d face_portal(const Frame& f, std::uint32_t x, std::uint32_t y, std::uint32_t z, int dir);

}  // namespace ebp::detail
