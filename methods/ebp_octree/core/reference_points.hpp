#pragma once
/// Where a leaf's reference point is looked for: the builder picks the first candidate off every
/// face plane; the inside query retries the others when the exact parity test needs it.
#include <vector>

#include "harness/core/geometry.hpp"

namespace ebp {

using bvhbench::Vec3d;

/// Fixed offsets, in fractions of the half cell from the cell centre, of the candidate reference
/// points of a leaf (the first near the centre, then a Halton sequence inside (-0.45, 0.45)^3).
const std::vector<Vec3d>& ref_offsets();

}  // namespace ebp
