#pragma once
/// A LeafTri's face normal in 32 bits: the octahedral map of the unit sphere onto the square
/// [-1, 1]^2 (Meyer et al., "On floating-point normal vectors", 2010), each coordinate a signed
/// 16-bit fixed-point number (k / 32767). The face plane is only a filter in front of the exact
/// predicates (DESIGN.md, "Inside"), so a quantized normal costs nothing in exactness: the
/// leaf's error bound (Leaf::eps) is widened by the normal's angular error, which the encoder
/// keeps under kFaceNormalError.
///
/// The decoded vector is not normalized (its length is in [1/sqrt(3), 1]): a side test only needs
/// the sign of v.(p - x0), and the distance search divides by |v| (face_plane_distance). Every
/// implementation (this scalar one and the kernels' SIMD ones, leaf_kernels.cpp) evaluates the
/// same float operations in the same order, so they give the same bits.
#include <cmath>
#include <cstdint>
#include <cstring>

#include "harness/core/geometry.hpp"

namespace ebp {

/// Bound on the angle (in radians, and on |v/|v| - n|) between a unit face normal n and the
/// direction of its decoded code. The 16-bit octahedral grid's worst case is 4.3e-5 (the encoder
/// keeps the best of the four grid points around n; measured over 10M random unit normals); a
/// normal the encoder cannot bring under this bound gets no plane (kNoPlane): its side tests go
/// exact, so the bound is a cost, never a correctness, matter.
inline constexpr double kFaceNormalError = 5e-5;

/// A leaf's bound (Leaf::eps) on the error of a face-plane value v.(p - centre) - d at points p
/// within `radius` of the leaf's centre (the radius covers the cell and every vertex of the leaf's
/// triangles): the float rounding of the value (2e-6 x radius; twice that after the distance
/// search divides by |v| >= 1/sqrt(3)) and the normal's direction (normal_error, the largest
/// encoder error of the leaf's normals, x |p - a|, |p - a| <= 2 radius).
inline double leaf_plane_eps(double radius, double normal_error) { return (4e-6 + 2 * normal_error) * radius; }
/// For points farther out, the bound's growth per unit of |p - centre| (1-norm).
inline constexpr double kPlaneEpsGrowth = 2e-6 + kFaceNormalError;

/// The fixed-point scale of the code's two halves.
inline constexpr float kOctScale = 1.0f / 32767.0f;

/// The decoded (unnormalized) normal of an octahedral code: u = low 16 bits, v = high 16 bits,
/// both signed. z = 1 - |u| - |v|; on the lower hemisphere (z < 0) the square's corners fold back.
inline void decode_face_normal(std::uint32_t code, float out[3]) {
  const float u = float(std::int32_t(code << 16) >> 16) * kOctScale;
  const float v = float(std::int32_t(code) >> 16) * kOctScale;
  const float z = (1.0f - std::fabs(u)) - std::fabs(v);
  const float t = -z > 0.0f ? -z : 0.0f;
  out[0] = u - std::copysign(t, u);
  out[1] = v - std::copysign(t, v);
  out[2] = z;
}

/// The code whose decoded direction is nearest the unit normal n (of the four grid points around
/// its octahedral image), and that direction's error |v/|v| - n| in *err.
inline std::uint32_t encode_face_normal(const bvhbench::Vec3d& n, double* err) {
  const double l1 = std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z);
  double u = n.x / l1, v = n.y / l1;
  if (n.z < 0) {
    const double fu = (1 - std::fabs(v)) * (u >= 0 ? 1 : -1), fv = (1 - std::fabs(u)) * (v >= 0 ? 1 : -1);
    u = fu, v = fv;
  }
  std::uint32_t best = 0;
  double best_err = 1e300;
  for (int i = 0; i < 4; ++i) {
    const double qu = (i & 1) ? std::ceil(u * 32767) : std::floor(u * 32767);
    const double qv = (i & 2) ? std::ceil(v * 32767) : std::floor(v * 32767);
    const auto iu = std::int32_t(std::fmax(-32767.0, std::fmin(32767.0, qu)));
    const auto iv = std::int32_t(std::fmax(-32767.0, std::fmin(32767.0, qv)));
    const std::uint32_t code = (std::uint32_t(iu) & 0xFFFFu) | (std::uint32_t(iv) << 16);
    float f[3];
    decode_face_normal(code, f);
    const bvhbench::Vec3d w{double(f[0]), double(f[1]), double(f[2])};
    const double e = norm(w / norm(w) - n);
    if (e < best_err) best_err = e, best = code;
  }
  *err = best_err;
  return best;
}

}  // namespace ebp
