#pragma once
/// Triangle / axis-aligned box kernels used to distribute triangles to leaf cells and to bound
/// the geometry of a cell.
///
///  - tri_box_overlap: Akenine-Moller's separating-axis test (13 axes), in double, made
///    *conservative*: the box is grown by a relative margin (kOverlapMargin of its size plus the
///    triangle's extent) so that rounding can never separate a triangle that touches the closed
///    box. A triangle is therefore listed in every cell it touches (ties included), and at worst in
///    a cell it misses by less than the margin, which costs time, never correctness.
///  - clip_triangle_to_box: Sutherland-Hodgman clipping of a triangle to a box (the same grown
///    box), giving the polygon triangle ∩ box whose vertices bound the cell's geometry.
#include <array>
#include <cmath>
#include <vector>

#include "harness/core/geometry.hpp"

namespace ebp {

using bvhbench::Vec3d;

/// Relative growth of boxes in the overlap and clipping tests (see above).
inline constexpr double kOverlapMargin = 1e-9;

/// Half-size growth used by both tests for a box of half-size h and a triangle (a, b, c) given
/// relative to the box centre.
inline double overlap_slack(const Vec3d& h, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  double m = std::max({h.x, h.y, h.z});
  for (const Vec3d* v : {&a, &b, &c}) m = std::max({m, std::fabs(v->x), std::fabs(v->y), std::fabs(v->z)});
  return kOverlapMargin * m;
}

/// Does triangle (a, b, c) touch the closed box [lo, hi]? Conservative (see above).
inline bool tri_box_overlap(const Vec3d& lo, const Vec3d& hi, const Vec3d& a0, const Vec3d& b0,
                            const Vec3d& c0) {
  const Vec3d c = (lo + hi) * 0.5;
  Vec3d h = (hi - lo) * 0.5;
  const Vec3d v0 = a0 - c, v1 = b0 - c, v2 = c0 - c;
  const double s = overlap_slack(h, v0, v1, v2);
  h = h + Vec3d(s, s, s);
  // 1. the box's face normals: the triangle's bounding box against the box.
  for (int i = 0; i < 3; ++i) {
    const double mn = std::min({v0[i], v1[i], v2[i]}), mx = std::max({v0[i], v1[i], v2[i]});
    if (mn > h[i] || mx < -h[i]) return false;
  }
  // 2. the nine cross products of the triangle's edges with the box's axes.
  const Vec3d e[3] = {v1 - v0, v2 - v1, v0 - v2};
  const Vec3d* v[3] = {&v0, &v1, &v2};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      Vec3d axis;  // e[i] x unit_j
      if (j == 0) axis = {0, e[i].z, -e[i].y};
      else if (j == 1) axis = {-e[i].z, 0, e[i].x};
      else axis = {e[i].y, -e[i].x, 0};
      const double p0 = dot(axis, *v[0]), p1 = dot(axis, *v[1]), p2 = dot(axis, *v[2]);
      const double r = h.x * std::fabs(axis.x) + h.y * std::fabs(axis.y) + h.z * std::fabs(axis.z);
      // Slack for the rounding of the projections themselves.
      const double tol = 1e-12 * (std::fabs(p0) + std::fabs(p1) + std::fabs(p2) + r);
      if (std::min({p0, p1, p2}) > r + tol || std::max({p0, p1, p2}) < -r - tol) return false;
    }
  }
  // 3. the triangle's plane against the box.
  const Vec3d n = cross(e[0], v2 - v0);
  const double d = dot(n, v0);
  const double r = h.x * std::fabs(n.x) + h.y * std::fabs(n.y) + h.z * std::fabs(n.z);
  const double tol = 1e-12 * (std::fabs(d) + r);
  if (std::fabs(d) > r + tol) return false;
  return true;
}

/// Clips triangle (a, b, c) to the closed box [lo, hi] grown by the overlap slack. Appends the
/// vertices of the (convex) polygon of the intersection to `out` (nothing if it is empty).
inline void clip_triangle_to_box(const Vec3d& lo, const Vec3d& hi, const Vec3d& a, const Vec3d& b,
                                 const Vec3d& c, std::vector<Vec3d>& out) {
  const Vec3d ctr = (lo + hi) * 0.5;
  const Vec3d h0 = (hi - lo) * 0.5;
  const double s = overlap_slack(h0, a - ctr, b - ctr, c - ctr);
  const Vec3d glo = lo - Vec3d(s, s, s), ghi = hi + Vec3d(s, s, s);
  // Fast path: the triangle is inside the box.
  if (glo.x <= std::min({a.x, b.x, c.x}) && std::max({a.x, b.x, c.x}) <= ghi.x &&
      glo.y <= std::min({a.y, b.y, c.y}) && std::max({a.y, b.y, c.y}) <= ghi.y &&
      glo.z <= std::min({a.z, b.z, c.z}) && std::max({a.z, b.z, c.z}) <= ghi.z) {
    out.push_back(a);
    out.push_back(b);
    out.push_back(c);
    return;
  }
  Vec3d buf0[16], buf1[16];
  int n = 3;
  buf0[0] = a;
  buf0[1] = b;
  buf0[2] = c;
  Vec3d* in = buf0;
  Vec3d* res = buf1;
  for (int axis = 0; axis < 3 && n > 0; ++axis) {
    for (int side = 0; side < 2 && n > 0; ++side) {
      // keep: side 0 -> x[axis] >= glo[axis]; side 1 -> x[axis] <= ghi[axis]
      const double bound = side == 0 ? glo[axis] : ghi[axis];
      auto inside = [&](const Vec3d& p) { return side == 0 ? p[axis] >= bound : p[axis] <= bound; };
      int m = 0;
      for (int i = 0; i < n; ++i) {
        const Vec3d& P = in[i];
        const Vec3d& Q = in[(i + 1) % n];
        const bool pin = inside(P), qin = inside(Q);
        if (pin) res[m++] = P;
        if (pin != qin) {
          const double t = (bound - P[axis]) / (Q[axis] - P[axis]);
          Vec3d X = P + (Q - P) * t;
          X[axis] = bound;  // exactly on the clipping plane
          res[m++] = X;
        }
      }
      n = m;
      std::swap(in, res);
    }
  }
  for (int i = 0; i < n; ++i) out.push_back(in[i]);
}

}  // namespace ebp
