#pragma once
/// What `bvhbench mesh-info` says about a mesh beyond what the reader saw: bounds, how its
/// edges are shared (is it closed?), degenerate triangles, unused vertices. Edges are pairs of
/// vertex *indices*: two vertices at the same position with different indices are different
/// vertices (an OBJ with texture seams is open along them; an STL is welded by its reader).
#include <cstdint>

#include "harness/core/geometry.hpp"

namespace bvhbench {

struct Mesh;

struct MeshStats {
  Box3d bounds;                          ///< of every vertex, referenced or not
  std::uint64_t unreferenced_vertices = 0;  ///< used by no triangle
  /// Edges: unordered pairs {u, v} of distinct vertex indices that are a side of some triangle
  /// (a triangle (a, a, b) has the sides a-b and b-a; a-a is not an edge).
  std::uint64_t edges = 0;
  std::uint64_t boundary_edges = 0;      ///< used by one triangle side
  std::uint64_t nonmanifold_edges = 0;   ///< used by three or more triangle sides
  std::uint64_t misoriented_edges = 0;   ///< used by two sides in the same direction
  std::uint64_t unbalanced_edges = 0;    ///< used more often in one direction than the other
  /// Triangles with a repeated vertex index or three collinear corners (coinciding included),
  /// decided exactly: zero area. Valid input, counted.
  std::uint64_t degenerate_triangles = 0;

  /// Closed: every edge is used by exactly two triangles, once in each direction — a
  /// watertight, edge-manifold, consistently oriented surface (and at least one edge).
  bool closed() const { return edges > 0 && boundary_edges == 0 && nonmanifold_edges == 0 && misoriented_edges == 0; }
  /// Every edge is used as often in each direction (non-manifold edges allowed): what the
  /// oracle (its `exact` inside definition) and the EBP-Octree's `closed` flag mean by closed.
  bool balanced() const { return edges > 0 && unbalanced_edges == 0; }
};

/// The statistics of `mesh` (O(F log F) time, 8 bytes per triangle side of scratch memory).
MeshStats mesh_stats(const Mesh& mesh);

}  // namespace bvhbench
