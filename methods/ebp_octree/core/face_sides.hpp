#pragma once
/// Derived: the faces whose front is outside and back inside over their whole interior, on
/// closed meshes (DESIGN.md, "The sign from the closest face"). The distance query takes a
/// point's sign from such a face when the face is the point's only closest triangle by a margin:
/// then the segment from the point to its closest point crosses no triangle, and the point is
/// outside (winding number 0) in front of the face and inside (1) behind it.
///
/// A face qualifies when
///   - it is clean: no other triangle meets it but in the vertices and the edge they share (exact
///     tests on every pair of a leaf's triangles whose boxes meet; a pair sharing a vertex only in
///     the leaf that owns that vertex, which lists both), so the winding number just in front of
///     it is one value over the whole face; and
///   - that value is 0: counted exactly along the segment to a face's centroid from the reference
///     point of the centroid's octant of its leaf (the segment lies in the leaf's cell, so the
///     leaf's triangles are all that can cross it), once for each set of a leaf's clean faces
///     joined by edges that only they share in opposite directions (their fronts are one region).
/// Anything these exact tests cannot decide leaves the face out; the query then asks the inside
/// query, as it does for every face on an open mesh.
#include "methods/ebp_octree/core/octree.hpp"

namespace ebp {

/// Recomputes tree.front_outside (a bit per input triangle; empty when the tree is not closed).
/// Called where a whole tree is built or loaded (build_octree, StoreReader::load_all), after
/// compute_leaf_blocks; a store's page is decoded without it (the query then asks the inside
/// query, with the same answers). `threads` > 1 runs the leaves in parallel.
void compute_face_sides(Octree& tree, int threads = 1);

/// Whether input triangle `tri`'s front is outside and its back inside (compute_face_sides).
inline bool front_outside(const Octree& tree, std::uint32_t tri) {
  const std::size_t w = tri >> 6;
  return w < tree.front_outside.size() && ((tree.front_outside[w] >> (tri & 63u)) & 1u);
}

}  // namespace ebp
