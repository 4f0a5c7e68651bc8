// The fixed candidate offsets of a leaf's reference point (reference_points.hpp).
#include "methods/ebp_octree/core/reference_points.hpp"

namespace ebp {

/// Fixed offsets (fractions of the half cell) of the candidate reference points. The first is
/// near the centre; the rest are a Halton (2, 3, 5) sequence in (-0.45, 0.45)^3.
const std::vector<Vec3d>& ref_offsets() {
  static const std::vector<Vec3d> offs = [] {
    std::vector<Vec3d> v{{0.0137, 0.0291, 0.0073}};
    auto halton = [](int i, int b) {
      double f = 1, r = 0;
      while (i > 0) { f /= b; r += f * (i % b); i /= b; }
      return r;
    };
    for (int i = 1; i < 24; ++i)
      v.push_back({0.9 * (halton(i, 2) - 0.5), 0.9 * (halton(i, 3) - 0.5), 0.9 * (halton(i, 5) - 0.5)});
    return v;
  }();
  return offs;
}

}  // namespace ebp
