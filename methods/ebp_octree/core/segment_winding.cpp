// Exact winding-number change along a segment: orient3d and the segment-triangle classification
// of predicates.hpp over each non-degenerate triangle of a list.
#include "methods/ebp_octree/core/segment_winding.hpp"

#include <vector>

#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/predicates.hpp"

namespace ebp {

bool segment_winding(const Vec3d& p, const Vec3d& q, const LeafTri* const* list, std::size_t n, int* delta) {
  int w = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const LeafTri& t = *list[i];
    if (t.flags() & kDegenerate) continue;
    const Vec3d a = to_d(t.a), b = to_d(t.b), c = to_d(t.c);
    const int sp = orient3d(a, b, c, p), sq = orient3d(a, b, c, q);
    if (sp == 0 && sq == 0) {
      // The segment lies in the triangle's plane: degenerate if it may meet the triangle
      // (conservatively: if the bounding boxes overlap).
      Box3d sb, tb;
      sb.add(p); sb.add(q); tb.add(a); tb.add(b); tb.add(c);
      if (sb.lo.x <= tb.hi.x && tb.lo.x <= sb.hi.x && sb.lo.y <= tb.hi.y && tb.lo.y <= sb.hi.y &&
          sb.lo.z <= tb.hi.z && tb.lo.z <= sb.hi.z)
        return false;
      continue;
    }
    const Cross r = sq != 0 ? segment_triangle(p, q, sp, sq, a, b, c) : segment_triangle(q, p, sq, sp, a, b, c);
    if (r == Cross::degenerate || r == Cross::on_p) return false;
    if (r == Cross::proper) w += sp > 0 ? 1 : -1;
  }
  *delta = w;
  return true;
}

bool segment_winding(const Vec3d& p, const Vec3d& q, const LeafTri* list, std::size_t n, int* delta) {
  std::vector<const LeafTri*> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = list + i;
  return segment_winding(p, q, v.data(), n, delta);
}

}  // namespace ebp
