// Exact fallbacks of the predicates (CGAL's Epick: static filter, interval filter, then exact
// arithmetic). Kept in one translation unit so that only it pays for the CGAL headers.
#include "methods/ebp_octree/core/predicates.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

namespace ebp {

thread_local unsigned long long g_orient_exact_calls = 0;

namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
K::Point_3 P(const Vec3d& v) { return K::Point_3(v.x, v.y, v.z); }
}  // namespace

int orient3d_exact(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
  // CGAL::orientation(p, q, r, s) is the sign of det[q - p, r - p, s - p] = ((q-p) x (r-p)).(s-p),
  // the same convention as ours.
  return int(CGAL::orientation(P(a), P(b), P(c), P(d)));
}

bool collinear_exact(const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  return CGAL::collinear(P(a), P(b), P(c));
}

}  // namespace ebp
