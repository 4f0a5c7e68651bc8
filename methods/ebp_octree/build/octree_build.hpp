#pragma once
/// The in-memory EBP-Octree build (octree_build.cpp; the external-memory build of a store is
/// external_build.hpp).
#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "methods/ebp_octree/core/build_params.hpp"
#include "methods/ebp_octree/core/octree.hpp"

namespace ebp {

/// The EBP-Octree over `vertices` (#V) and `triangles` (#F, indices into vertices). Triangles may
/// be degenerate or repeated; #F >= 1. Throws std::invalid_argument on an index out of range or a
/// non-finite coordinate. `progress` (optional) receives fractions in [0, 1].
Octree build_octree(const std::vector<Vec3d>& vertices, const std::vector<std::array<std::uint32_t, 3>>& triangles,
                    const BuildParams& params, const std::function<void(double)>& progress = nullptr);

}  // namespace ebp
