#pragma once
/// Exact geometric predicates on double coordinates, with a floating-point filter inlined and an
/// exact fallback out of line (CGAL's Epick kernel, predicates.cpp).
///
/// orient3d(a, b, c, d) = sign of ((b - a) x (c - a)) . (d - a): +1 when d is on the side the
/// right-hand normal of triangle (a, b, c) points to (the outer side of an outward-oriented face),
/// -1 on the other side, 0 exactly on the plane. Exact for any finite doubles.
#include <cmath>

#include "harness/core/geometry.hpp"

namespace ebp {

using bvhbench::Vec3d;

/// x rounded to the nearest float, as a double. The empty asm keeps the rounding: GCC 12.2 at -O2
/// and above drops `double(float(x))` when its SLP vectorizer pairs two of them (x and y of a
/// vector built from a braced list), which silently broke the consistency between the float
/// geometry and its double copy.
inline double round_to_float(double x) {
  float f = float(x);
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
  asm("" : "+x"(f));
#elif defined(__GNUC__)
  asm("" : "+r"(f));
#endif
  return double(f);
}
inline Vec3d round_to_float(const Vec3d& v) {
  return {round_to_float(v.x), round_to_float(v.y), round_to_float(v.z)};
}

/// Exact sign, no filter (CGAL Epick). Out of line: rarely reached.
int orient3d_exact(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d);
/// Exact: are a, b, c collinear (or coincident)? A zero-area triangle.
bool collinear_exact(const Vec3d& a, const Vec3d& b, const Vec3d& c);

/// Counts how often the filter failed (for tests and profiling; not thread-safe, informative).
extern thread_local unsigned long long g_orient_exact_calls;

inline int orient3d(const Vec3d& a, const Vec3d& b, const Vec3d& c, const Vec3d& d) {
  // Shewchuk's orient3d with his first-stage error bound A ((7 + 56 eps) eps times the
  // permanent), which accounts for the rounding of the differences as well. Shewchuk's sign
  // convention is the opposite of ours, hence the negations.
  const double adx = a.x - d.x, bdx = b.x - d.x, cdx = c.x - d.x;
  const double ady = a.y - d.y, bdy = b.y - d.y, cdy = c.y - d.y;
  const double adz = a.z - d.z, bdz = b.z - d.z, cdz = c.z - d.z;
  const double bdxcdy = bdx * cdy, cdxbdy = cdx * bdy;
  const double cdxady = cdx * ady, adxcdy = adx * cdy;
  const double adxbdy = adx * bdy, bdxady = bdx * ady;
  const double det = adz * (bdxcdy - cdxbdy) + bdz * (cdxady - adxcdy) + cdz * (adxbdy - bdxady);
  const double permanent = (std::fabs(bdxcdy) + std::fabs(cdxbdy)) * std::fabs(adz) +
                           (std::fabs(cdxady) + std::fabs(adxcdy)) * std::fabs(bdz) +
                           (std::fabs(adxbdy) + std::fabs(bdxady)) * std::fabs(cdz);
  const double errbound = 7.7715611723761027e-16 * permanent;
  if (det > errbound) return -1;
  if (-det > errbound) return 1;
  ++g_orient_exact_calls;
  return orient3d_exact(a, b, c, d);
}

/// Result of crossing a segment with a triangle, for parity counting.
enum class Cross : unsigned char {
  none,        ///< the closed segment misses the triangle (or touches it only where parity ignores)
  proper,      ///< the open segment crosses the triangle's interior exactly once
  degenerate,  ///< through an edge or a vertex, or the segment lies in the triangle's plane
  on_p,        ///< the first endpoint p lies on the (closed) triangle
};

/// Exact crossing of segment [p, q] with triangle (a, b, c). Preconditions: the triangle is not
/// degenerate (not collinear); `sq` = orient3d(a, b, c, q) != 0 and `sp` = orient3d(a, b, c, p)
/// given by the caller (who often knows them from a cheaper test).
inline Cross segment_triangle(const Vec3d& p, const Vec3d& q, int sp, int sq, const Vec3d& a,
                              const Vec3d& b, const Vec3d& c) {
  if (sp == sq) return Cross::none;  // both strictly on one side
  const int e1 = orient3d(p, q, a, b);
  const int e2 = orient3d(p, q, b, c);
  const int e3 = orient3d(p, q, c, a);
  if ((e1 > 0 || e2 > 0 || e3 > 0) && (e1 < 0 || e2 < 0 || e3 < 0)) return Cross::none;
  // All of one sign (or zero): the line pq meets the closed triangle.
  if (sp == 0) return Cross::on_p;
  if (e1 == 0 || e2 == 0 || e3 == 0) return Cross::degenerate;
  return Cross::proper;
}

}  // namespace ebp
