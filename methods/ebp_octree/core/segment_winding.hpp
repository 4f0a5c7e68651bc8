#pragma once
/// The exact winding-number change along a segment over a leaf's triangles (predicates.hpp).
#include <cstddef>

#include "methods/ebp_octree/core/octree.hpp"

namespace ebp {

/// Winding-number change along segment p -> q over the (non-degenerate) triangles of `list`,
/// exactly: the sum over proper crossings of +1 (entering: from the side the normal points to, to
/// the other) or -1 (leaving), i.e. w(q) - w(p). Returns false (and leaves *delta alone) if the
/// segment passes through an edge or a vertex, lies in a triangle's plane over it, or an endpoint
/// lies on a triangle. Build-time helper, exposed for tests.
bool segment_winding(const Vec3d& p, const Vec3d& q, const LeafTri* const* list, std::size_t n, int* delta);
bool segment_winding(const Vec3d& p, const Vec3d& q, const LeafTri* list, std::size_t n, int* delta);

}  // namespace ebp
