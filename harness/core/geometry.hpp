#pragma once
/// Small fixed-size vector algebra and the exact-in-double point/triangle kernels shared by the
/// harness and the brute-force reference. Header-only so that hot loops inline.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>

namespace bvhbench {

template <class T>
struct Vec3 {
  T x{}, y{}, z{};
  constexpr Vec3() = default;
  constexpr Vec3(T x_, T y_, T z_) : x(x_), y(y_), z(z_) {}
  template <class U>
  constexpr explicit Vec3(const Vec3<U>& o) : x(T(o.x)), y(T(o.y)), z(T(o.z)) {}
  constexpr explicit Vec3(const std::array<T, 3>& a) : x(a[0]), y(a[1]), z(a[2]) {}
  constexpr T& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr T operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }
  constexpr Vec3 operator+(const Vec3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  constexpr Vec3 operator-(const Vec3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  constexpr Vec3 operator-() const { return {-x, -y, -z}; }
  constexpr Vec3 operator*(T s) const { return {x * s, y * s, z * s}; }
  constexpr Vec3 operator/(T s) const { return {x / s, y / s, z / s}; }
  constexpr Vec3& operator+=(const Vec3& o) { x += o.x; y += o.y; z += o.z; return *this; }
  constexpr Vec3& operator-=(const Vec3& o) { x -= o.x; y -= o.y; z -= o.z; return *this; }
  constexpr Vec3& operator*=(T s) { x *= s; y *= s; z *= s; return *this; }
  constexpr bool operator==(const Vec3& o) const { return x == o.x && y == o.y && z == o.z; }
  constexpr bool operator!=(const Vec3& o) const { return !(*this == o); }
};
using Vec3d = Vec3<double>;
using Vec3f = Vec3<float>;

template <class T> constexpr T dot(const Vec3<T>& a, const Vec3<T>& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
template <class T> constexpr Vec3<T> cross(const Vec3<T>& a, const Vec3<T>& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
template <class T> inline T norm(const Vec3<T>& a) { return std::sqrt(dot(a, a)); }
template <class T> constexpr T squared_norm(const Vec3<T>& a) { return dot(a, a); }
/// The sum of triangle (a, b, c)'s edge lengths, in one order: every mean edge length (a loaded
/// mesh's, a paged one's, the EBP-Octree's frame) adds it, so they are the same double.
template <class T> inline T perimeter(const Vec3<T>& a, const Vec3<T>& b, const Vec3<T>& c) {
  return norm(b - a) + norm(c - b) + norm(a - c);
}
template <class T> inline Vec3<T> normalized(const Vec3<T>& a) {
  T n = norm(a);
  return n > T(0) ? a / n : Vec3<T>{};
}
template <class T> constexpr Vec3<T> vmin(const Vec3<T>& a, const Vec3<T>& b) {
  return {std::min(a.x, b.x), std::min(a.y, b.y), std::min(a.z, b.z)};
}
template <class T> constexpr Vec3<T> vmax(const Vec3<T>& a, const Vec3<T>& b) {
  return {std::max(a.x, b.x), std::max(a.y, b.y), std::max(a.z, b.z)};
}

/// Axis-aligned box; empty() until something is added.
template <class T>
struct Box3 {
  Vec3<T> lo{std::numeric_limits<T>::infinity(), std::numeric_limits<T>::infinity(), std::numeric_limits<T>::infinity()};
  Vec3<T> hi{-std::numeric_limits<T>::infinity(), -std::numeric_limits<T>::infinity(), -std::numeric_limits<T>::infinity()};
  constexpr bool empty() const { return !(lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z); }
  constexpr void add(const Vec3<T>& p) { lo = vmin(lo, p); hi = vmax(hi, p); }
  constexpr void add(const Box3& b) { lo = vmin(lo, b.lo); hi = vmax(hi, b.hi); }
  constexpr Vec3<T> extent() const { return hi - lo; }
  T diagonal() const { return empty() ? T(0) : norm(hi - lo); }
  constexpr bool contains(const Vec3<T>& p) const {
    return p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y && p.z >= lo.z && p.z <= hi.z;
  }
  /// Squared distance from p to the box (0 inside).
  constexpr T squared_distance(const Vec3<T>& p) const {
    T d = 0;
    for (int i = 0; i < 3; ++i) {
      T v = std::max({lo[i] - p[i], T(0), p[i] - hi[i]});
      d += v * v;
    }
    return d;
  }
};
using Box3d = Box3<double>;

/// Which feature of a triangle a closest point lies on.
enum class TriangleFeature : std::uint8_t { face, edge_ab, edge_bc, edge_ca, vertex_a, vertex_b, vertex_c };

/// Closest point on triangle (a, b, c) to p (Ericson, Real-Time Collision Detection, 5.1.5),
/// with the feature it lies on. Degenerate triangles (zero area, collapsed) are handled: the
/// result is the closest point of the segment(s)/point they collapse to.
template <class T>
inline Vec3<T> closest_point_on_triangle(const Vec3<T>& p, const Vec3<T>& a, const Vec3<T>& b,
                                         const Vec3<T>& c, TriangleFeature* feature = nullptr) {
  TriangleFeature f_dummy;
  TriangleFeature& f = feature ? *feature : f_dummy;
  const Vec3<T> ab = b - a, ac = c - a, ap = p - a;
  const T d1 = dot(ab, ap), d2 = dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) { f = TriangleFeature::vertex_a; return a; }
  const Vec3<T> bp = p - b;
  const T d3 = dot(ab, bp), d4 = dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) { f = TriangleFeature::vertex_b; return b; }
  const T vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0 && d1 - d3 > 0) {
    f = TriangleFeature::edge_ab;
    return a + ab * (d1 / (d1 - d3));
  }
  const Vec3<T> cp = p - c;
  const T d5 = dot(ab, cp), d6 = dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) { f = TriangleFeature::vertex_c; return c; }
  const T vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0 && d2 - d6 > 0) {
    f = TriangleFeature::edge_ca;
    return a + ac * (d2 / (d2 - d6));
  }
  const T va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0 && (d4 - d3) + (d5 - d6) > 0) {
    f = TriangleFeature::edge_bc;
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  }
  const T denom = va + vb + vc;
  if (!(denom > 0)) {
    // Degenerate (zero-area) triangle that fell through: take the best of its three edges.
    auto seg = [&](const Vec3<T>& s, const Vec3<T>& e) {
      Vec3<T> d = e - s;
      T len2 = dot(d, d);
      T t = len2 > 0 ? std::clamp(dot(p - s, d) / len2, T(0), T(1)) : T(0);
      return s + d * t;
    };
    Vec3<T> q[3] = {seg(a, b), seg(b, c), seg(c, a)};
    TriangleFeature fs[3] = {TriangleFeature::edge_ab, TriangleFeature::edge_bc, TriangleFeature::edge_ca};
    int best = 0;
    for (int i = 1; i < 3; ++i)
      if (squared_norm(q[i] - p) < squared_norm(q[best] - p)) best = i;
    f = fs[best];
    return q[best];
  }
  f = TriangleFeature::face;
  const T v = vb / denom, w = vc / denom;
  return a + ab * v + ac * w;
}

/// Signed solid angle subtended by triangle (a, b, c) at p, divided by 4*pi (Van Oosterom and
/// Strackee 1983). Summed over a closed, outward-oriented mesh it is 1 inside and 0 outside: the
/// generalized winding number (Jacobson et al. 2013), defined for open meshes too.
inline double triangle_winding(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  const Vec3d u = a - p, v = b - p, w = c - p;
  const double lu = norm(u), lv = norm(v), lw = norm(w);
  const double det = dot(u, cross(v, w));
  const double den = lu * lv * lw + dot(u, v) * lw + dot(v, w) * lu + dot(w, u) * lv;
  constexpr double inv_two_pi = 0.15915494309189533577;  // 1 / (2 pi)
  return std::atan2(det, den) * inv_two_pi;
}

/// Unit normal of triangle (a, b, c) by the right-hand rule; zero for a degenerate triangle.
template <class T>
inline Vec3<T> triangle_normal(const Vec3<T>& a, const Vec3<T>& b, const Vec3<T>& c) {
  return normalized(cross(b - a, c - a));
}

}  // namespace bvhbench
