#pragma once
/// The parameters of the EBP-Octree's build (in memory: Octree::build; external: build/external_build.hpp),
/// recorded in a store's header.
#include "methods/ebp_octree/core/octcode.hpp"

namespace ebp {

struct BuildParams {
  double leaf_factor = 5.0;     ///< leaf cell size >= leaf_factor x average edge length
  int max_planes = 8;           ///< bounding planes per node (at most)
  double cluster_angle = 30.0;  ///< degrees: normals closer than this share one plane
  int threads = 1;              ///< > 1: TBB parallel build
  int max_level = kMaxLevel;    ///< clamp of the leaf level (1..19)
};

}  // namespace ebp
