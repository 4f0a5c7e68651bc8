#pragma once
/// The structure stores coordinates as float triples; the exact predicates and the closest-point
/// computations take them as Vec3d (exactly: every float is a double).
#include "harness/core/geometry.hpp"

namespace ebp {

inline bvhbench::Vec3d to_d(const float* f) { return {double(f[0]), double(f[1]), double(f[2])}; }

}  // namespace ebp
