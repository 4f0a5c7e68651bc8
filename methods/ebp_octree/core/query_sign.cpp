// The distance's sign (Query::distance): after the unsigned distance, from the closest face
// where it decides it exactly (face_sides.hpp), the previous query's sign where the chained sign
// holds (certificate.hpp), else the inside query (query_inside.cpp).
#include "methods/ebp_octree/core/certificate.hpp"
#include "methods/ebp_octree/core/face_sides.hpp"
#include "methods/ebp_octree/core/float_coords.hpp"
#include "methods/ebp_octree/core/predicates.hpp"
#include "methods/ebp_octree/core/query.hpp"

namespace ebp {

// The sign from the closest face (face_sides.hpp): LeafTri k, at distance d from p, is the one
// triangle nearest p when every other one tested is farther than d + 2 tol (runner2, squared;
// nothing farther than d + tol went untested, and tol bounds the rounding of a distance); then
// nothing crosses the segment from p to its closest point, which lies inside the face, and p's
// side of the face is its side of the solid where the face's front is outside.
void Query::take_face_side(const Vec3d& p, std::uint32_t k, double d, double runner2, double tol) {
  if (!face_sign_ || k >= t_.tris.size()) return;
  const LeafTri& t = t_.tris[k];
  const double m = d + 2 * tol;
  if (runner2 > m * m && front_outside(t_, t.tri())) face_side_ = orient3d(to_d(t.a), to_d(t.b), to_d(t.c), p);
}

DistanceAnswer Query::distance(const Vec3d& p) {
  DistanceAnswer r = unsigned_distance(p);
  if (sign_after_distance(p, r.distance)) r.distance = -r.distance;
  return r;
}

bool Query::sign_after_distance(const Vec3d& p, double distance) {
  const bool track = coherent_ && t_.closed;
  if (face_side_ != 0) {
    ++counters.signs_from_face;
    const bool in = face_side_ < 0;  // winding number 1 behind the face, 0 in front
    if (track) {  // the coherent inside state moves to p, whose winding number is now known
      prev_ok_ = true;
      prev_p_ = p;
      prev_w_ = in ? 1 : 0;
    }
    if (track && chained_sign_) path_->answered(p, distance, in);
    return in;
  }
  bool in;
  if (track && chained_sign_) {
    // The chained sign (certificate.hpp): the previous point's, when the balls about it and p
    // that hold no surface cover the segment between them; the coherent inside state then moves
    // along (the winding number is the same at p), so that the next inside test steps from p.
    const Vec3d prev = path_->sign_point();
    if (path_->sign_chained(p, distance, certificate_tol(p, t_.root_lo, t_.root_size), &in)) {
      ++counters.signs_chained;
      if (prev_ok_ && prev_p_ == prev) prev_p_ = p;
    } else {
      in = inside(p);
    }
    path_->answered(p, distance, in);
  } else {
    in = inside(p);
  }
  return in;
}

}  // namespace ebp
