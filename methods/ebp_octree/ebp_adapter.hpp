#pragma once
/// What the two harness adapters of the EBP-Octree (in memory: ebp_method.cpp; out of core:
/// ooc_method.cpp) share: turning the library's answer into the harness's.
#include "methods/ebp_octree/core/query.hpp"
#include "harness/core/method.hpp"

#include <vector>

namespace bvhbench {

/// The work counters of both adapters, by the harness's names.
inline std::vector<Counter> ebp_counters(const ebp::QueryCounters& c) {
  return {{"nodes_visited", c.nodes_visited}, {"planes_tested", c.planes_tested},
          {"triangles_tested", c.triangles_tested}, {"hit_white", c.hit_white},
          {"hit_black", c.hit_black}, {"hit_convex", c.hit_convex},
          {"hit_concave", c.hit_concave}, {"hit_special", c.hit_special},
          {"exact_fallbacks", c.exact_fallbacks}, {"certificate_renewals", c.certificate_renewals},
          {"certificate_served", c.certificate_served}, {"signs_chained", c.signs_chained},
          {"signs_from_face", c.signs_from_face},
          {"near_served", c.near_served}, {"near_gathered", c.near_gathered},
          {"near_tested", c.near_tested}};
}

inline DistanceResult to_distance_result(const ebp::DistanceAnswer& a) {
  DistanceResult r;
  r.distance = a.distance;
  r.closest = a.closest;
  r.normal = a.normal;
  r.triangle = a.triangle;
  return r;
}

}  // namespace bvhbench
