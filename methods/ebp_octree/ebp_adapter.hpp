#pragma once
/// What the two harness adapters of the EBP-Octree (in memory: ebp_method.cpp; out of core:
/// ebp_cli.cpp) share: turning the library's answer into the harness's.
#include "methods/ebp_octree/core/query.hpp"
#include "harness/core/method.hpp"

namespace bvhbench {

inline DistanceResult to_distance_result(const ebp::DistanceAnswer& a) {
  DistanceResult r;
  r.distance = a.distance;
  r.closest = a.closest;
  r.normal = a.normal;
  r.triangle = a.triangle;
  return r;
}

}  // namespace bvhbench
