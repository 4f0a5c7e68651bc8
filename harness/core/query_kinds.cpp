// The query kinds: one registration entry each (see QueryKind in query_set.hpp). The generators
// live in query_kinds_*.cpp; their shared internals in query_kinds_detail.hpp.
#include <algorithm>
#include <vector>

#include "harness/core/mesh.hpp"
#include "harness/core/query_kinds_detail.hpp"
#include "harness/core/query_set.hpp"
#include "harness/core/rng.hpp"

namespace bvhbench {

namespace query_kinds_detail {

/// Uniform points in the mesh's bounding box enlarged by `margin` (fraction of the extent,
/// default 10%) on each side.
std::vector<Vec3d> random_points(const Mesh& mesh, std::size_t n, std::uint64_t seed,
                                 const Params& params) {
  Box3d b = mesh.bounds();
  const double margin = params.at("margin");
  Vec3d ext = b.extent();
  // A flat or point-like mesh still gets a box with volume.
  double pad = std::max({ext.x, ext.y, ext.z}) * 1e-3;
  if (!(pad > 0)) pad = 1.0;
  for (int i = 0; i < 3; ++i)
    if (!(ext[i] > 0)) { b.lo[i] -= pad; b.hi[i] += pad; ext[i] = 2 * pad; }
  Vec3d lo = b.lo - ext * margin, hi = b.hi + ext * margin;
  Rng rng(seed);
  std::vector<Vec3d> pts(n);
  for (auto& p : pts) {
    p.x = rng.uniform(lo.x, hi.x);
    p.y = rng.uniform(lo.y, hi.y);
    p.z = rng.uniform(lo.z, hi.z);
  }
  return pts;
}

}  // namespace query_kinds_detail

const std::vector<QueryKind>& query_kinds() {
  namespace d = query_kinds_detail;
  static const std::vector<QueryKind> kinds = {
      {"random", "uniform in the bounding box enlarged by `margin` of its extent on each side",
       {{"margin", 0.1}}, d::random_points, false},
      {"near",
       "area-weighted surface samples moved along the face normal by a Gaussian offset of "
       "standard deviation `sigma` times the bounding-box diagonal",
       {{"sigma", 0.01}}, d::near_points, false},
      {"haptic",
       "a simulated 1 kHz haptic probe: contact episodes that come in from free space, slide "
       "on the surface inside a contact band (+-band_mm) and leave; speeds in m/s with the "
       "bounding-box diagonal taken as model_size_m metres; replayed in order",
       {{"model_size_m", 0.3},
        {"rate_hz", 1000},
        {"max_speed", 0.5},
        {"slide_speed", 0.1},
        {"approach_speed", 0.2},
        {"approach_mm", 20},
        {"band_mm", 0.5},
        {"contact_ms", 2000},
        {"turn_rate", 1.5}},
       d::haptic_path, true},
      {"contact",
       "the haptic probe's contact phases alone (no approach or leave): every sample slides "
       "inside the contact band (+-band_mm) of the surface, the near-touching regime of a "
       "haptic loop; episodes of contact_ms start on new surface points; replayed in order",
       {{"model_size_m", 0.3},
        {"rate_hz", 1000},
        {"max_speed", 0.5},
        {"slide_speed", 0.1},
        {"band_mm", 0.5},
        {"contact_ms", 2000},
        {"turn_rate", 1.5}},
       d::contact_path, true},
      {"surface",
       "points exactly on the mesh: on vertices (share vertex_share), on edges (edge_share) "
       "and inside faces (the rest, area-weighted)",
       {{"vertex_share", 1.0 / 3}, {"edge_share", 1.0 / 3}}, d::surface_points, false},
  };
  return kinds;
}

}  // namespace bvhbench
