// The query kinds: one registration entry each (see QueryKind in query_set.hpp).
#include <vector>

#include "mesh.hpp"
#include "query_set.hpp"

namespace bvhbench {

namespace {

/// Uniform points in the mesh's bounding box enlarged by `margin` (fraction of the extent,
/// default 10%) on each side.
std::vector<Vec3d> random_points(const Mesh& mesh, std::size_t n, std::uint64_t seed,
                                 const std::map<std::string, double>& params) {
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

}  // namespace

const std::vector<QueryKind>& query_kinds() {
  static const std::vector<QueryKind> kinds = {
      {"random", "uniform in the bounding box enlarged by `margin` of its extent on each side",
       {{"margin", 0.1}}, random_points, false},
  };
  return kinds;
}

}  // namespace bvhbench
