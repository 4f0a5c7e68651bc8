#pragma once
/// Convex polytopes made by clipping a box with half-spaces n.x <= d: the bounding volumes of
/// EBP-Octree nodes (cell box ∩ bounding planes). Used at build time only, to offset an inner
/// node's planes to the support of its children's volumes and to measure tightness (volume).
#include <vector>

#include "harness/core/geometry.hpp"

namespace ebp {

using bvhbench::Vec3d;

class Polytope {
 public:
  /// The closed box [lo, hi].
  static Polytope box(const Vec3d& lo, const Vec3d& hi);
  /// Keeps the part with n.x <= d (n need not be unit).
  void clip(const Vec3d& n, double d);
  bool empty() const { return faces_.empty(); }
  /// Every vertex (with repeats across faces).
  std::vector<Vec3d> vertices() const;
  /// Volume (divergence theorem over the faces); 0 when empty.
  double volume() const;
  /// max over vertices of n.v (-inf when empty).
  double support(const Vec3d& n) const;

 private:
  std::vector<std::vector<Vec3d>> faces_;  // each convex, counter-clockwise seen from outside
};

}  // namespace ebp
