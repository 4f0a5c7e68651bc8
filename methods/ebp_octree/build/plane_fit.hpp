#pragma once
/// How the builder makes a bounding plane (leaves and inner nodes alike): a unit direction rounded
/// to float, its offset the support of the points, rounded up so that containment survives the
/// rounding. Internal to the builders.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "methods/ebp_octree/build/build_parts.hpp"
#include "methods/ebp_octree/core/predicates.hpp"

namespace ebp::detail {

/// Rounds a double up to the next float >= it.
inline float round_up(double d) {
  const double r = round_to_float(d);
  float f = float(r);
  if (r < d) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}

inline double box_support(const Vec3d& lo, const Vec3d& hi, const Vec3d& n) {
  return (n.x > 0 ? n.x * hi.x : n.x * lo.x) + (n.y > 0 ? n.y * hi.y : n.y * lo.y) +
         (n.z > 0 ? n.z * hi.z : n.z * lo.z);
}

/// Makes a float plane (root frame) from a unit direction and the support of `pts` (world).
inline void make_plane(const BuildContext& ctx, const Vec3d& n, const std::vector<Vec3d>& pts, Plane* out) {
  const Vec3d rc = ctx.f.root_centre;
  const Vec3d nd = round_to_float(n);
  double s = -std::numeric_limits<double>::infinity();
  for (const Vec3d& v : pts) s = std::max(s, dot(nd, v - rc));
  out->n[0] = float(nd.x); out->n[1] = float(nd.y); out->n[2] = float(nd.z);
  out->d = round_up(s + ctx.plane_margin);
}
inline void plane_world(const BuildContext& ctx, const Plane& p, Vec3d* n, double* d) {
  *n = Vec3d(double(p.n[0]), double(p.n[1]), double(p.n[2]));
  *d = double(p.d) + dot(*n, ctx.f.root_centre);
}

}  // namespace ebp::detail
