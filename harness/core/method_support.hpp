// Small pieces of geometry that several methods share: the float32 copy of a mesh that the
// method-precision contract asks for, and the face normal a method reports for a triangle of that
// copy. Header-only, so a method takes only what it uses.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "harness/core/geometry.hpp"

namespace bvhbench {

/// x rounded to the nearest float32, returned as a double.
/// Through a volatile: GCC 12.2's SLP vectorizer at -O2/-O3 folds the pairwise round trip
/// `Vec3d(Vec3f(v))` in a loop to a no-op for x and y (wrong code), so a plain cast back to double
/// may silently skip the rounding.
inline double round_to_float32(double x) {
  volatile float f = static_cast<float>(x);
  return f;
}

/// v with each coordinate rounded to the nearest float32 (see round_to_float32), in double.
inline Vec3d round_to_float32(const Vec3d& v) {
  return Vec3d(round_to_float32(v.x), round_to_float32(v.y), round_to_float32(v.z));
}

/// The #V float32 positions a method keeps (round to nearest), followed by `padding` zero
/// vertices (for libraries that read past the last vertex). The capacity is exactly
/// #V + padding, so `capacity() * sizeof(Vec3f)` is the memory it holds.
inline std::vector<Vec3f> float32_vertices(const std::vector<Vec3d>& vertices, std::size_t padding = 0) {
  std::vector<Vec3f> out(vertices.size() + padding);
  for (std::size_t i = 0; i < vertices.size(); ++i) out[i] = Vec3f(vertices[i]);
  return out;
}

/// Unit outward normal (right-hand rule) of triangle t over float32 vertices, computed in double
/// from the exact float values; zero for a degenerate triangle.
inline Vec3d face_normal(const std::vector<Vec3f>& vertices, const std::array<std::uint32_t, 3>& t) {
  return triangle_normal(Vec3d(vertices[t[0]]), Vec3d(vertices[t[1]]), Vec3d(vertices[t[2]]));
}

}  // namespace bvhbench
