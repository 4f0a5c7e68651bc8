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
std::vector<Vec3d> random_points_in_box(const Box3d& box, std::size_t n, std::uint64_t seed, const Params& params) {
  Box3d b = box;
  const double margin = params.get_real("margin");
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

std::vector<Vec3d> random_points(const TriangleSource& mesh, std::size_t n, std::uint64_t seed, const Params& params) {
  return random_points_in_box(mesh.summary().bounds, n, seed, params);
}

}  // namespace query_kinds_detail

namespace {

/// A real parameter of a query kind: its default as text (the value it reads back to is the
/// default), what it means, and its range ((min, max] when min_excluded).
ParamSpec real(const char* name, const char* default_value, const char* help, double min = -1e308,
               bool min_excluded = false, double max = 1e308) {
  ParamSpec p;
  p.name = name;
  p.type = ParamType::real;
  p.role = ParamRole::query;
  p.default_value = default_value;
  p.help = help;
  p.min = min;
  p.max = max;
  p.min_excluded = min_excluded;
  return p;
}

constexpr bool kAbove = true;  // min_excluded: the value must be > min

// The probe's parameters, shared by `haptic` and `contact` (query_kinds_haptic.cpp).
std::vector<ParamSpec> probe_params(bool approach_and_leave) {
  std::vector<ParamSpec> ps = {
      real("model_size_m", "0.3", "the bounding-box diagonal in metres", 0, kAbove),
      real("rate_hz", "1000", "samples per second", 0, kAbove),
      real("max_speed", "0.5", "the longest step, in m/s", 0, kAbove),
      real("slide_speed", "0.1", "the sliding speed's bound, in m/s", 0, kAbove),
  };
  if (approach_and_leave) {
    ps.push_back(real("approach_speed", "0.2", "the speed towards and away from the surface, in m/s", 0, kAbove));
    ps.push_back(real("approach_mm", "20", "where an approach starts, in mm off the surface", 0, kAbove));
  }
  ps.push_back(real("band_mm", "0.5", "the contact band's half-width, in mm", 0, kAbove));
  ps.push_back(real("contact_ms", "2000", "a contact episode's length, in ms", 0, kAbove));
  ps.push_back(real("turn_rate", "1.5", "how fast the heading turns, in rad/s", 0));
  return ps;
}

}  // namespace

const std::vector<QueryKind>& query_kinds() {
  namespace d = query_kinds_detail;
  static const std::vector<QueryKind> kinds = {
      {"random", "uniform in the bounding box enlarged by `margin` of its extent on each side",
       {real("margin", "0.1", "the box's enlargement on each side, as a fraction of its extent")},
       d::random_points, false, d::random_points_in_box},
      {"near",
       "area-weighted surface samples moved along the face normal by a Gaussian offset of "
       "standard deviation `sigma` times the bounding-box diagonal",
       {real("sigma", "0.01", "the offset's standard deviation, as a fraction of the bounding-box diagonal", 0)},
       d::near_points, false, nullptr},
      {"haptic",
       "a simulated 1 kHz haptic probe: contact episodes that come in from free space, slide "
       "on the surface inside a contact band (+-band_mm) and leave; speeds in m/s with the "
       "bounding-box diagonal taken as model_size_m metres; replayed in order",
       probe_params(true), d::haptic_path, true, nullptr},
      {"contact",
       "the haptic probe's contact phases alone (no approach or leave): every sample slides "
       "inside the contact band (+-band_mm) of the surface, the near-touching regime of a "
       "haptic loop; episodes of contact_ms start on new surface points; replayed in order",
       probe_params(false), d::contact_path, true, nullptr},
      {"surface",
       "points exactly on the mesh: on vertices (share vertex_share), on edges (edge_share) "
       "and inside faces (the rest, area-weighted)",
       {real("vertex_share", "0.3333333333333333", "the share of points on vertices", 0, false, 1),
        real("edge_share", "0.3333333333333333", "the share of points on edges", 0, false, 1)},
       d::surface_points, false, nullptr},
  };
  return kinds;
}

}  // namespace bvhbench
