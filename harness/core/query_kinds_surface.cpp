// Query kinds sampled on the surface: `near` (offset along the normal) and `surface` (exactly
// on vertices, edges and faces), with the area-weighted sampler they share.
#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "harness/core/query_kinds_detail.hpp"
#include "harness/core/query_set.hpp"
#include "harness/core/rng.hpp"
#include "harness/util/errors.hpp"

namespace bvhbench::query_kinds_detail {

AreaSampler::AreaSampler(const Mesh& mesh) {
  cdf_.resize(mesh.num_triangles());
  double sum = 0;
  for (std::size_t t = 0; t < cdf_.size(); ++t) {
    const Vec3d a = mesh.vertex(std::uint32_t(t), 0), b = mesh.vertex(std::uint32_t(t), 1),
                c = mesh.vertex(std::uint32_t(t), 2);
    sum += 0.5 * norm(cross(b - a, c - a));
    cdf_[t] = sum;
  }
  if (!(sum > 0) || !std::isfinite(sum))
    throw InputError(mesh.path + ": the mesh has no surface area to sample");
}

std::uint32_t AreaSampler::pick(double u) const {
  const double x = u * cdf_.back();
  // First triangle whose cumulative area exceeds x: zero-area triangles (equal cdf to their
  // predecessor) can never be the first to exceed it.
  auto it = std::upper_bound(cdf_.begin(), cdf_.end(), x);
  if (it == cdf_.end()) --it;
  return std::uint32_t(it - cdf_.begin());
}

Vec3d uniform_in_triangle(const Vec3d& a, const Vec3d& b, const Vec3d& c, double r1, double r2) {
  const double s = std::sqrt(r1);
  return a * (1 - s) + b * (s * (1 - r2)) + c * (s * r2);
}

std::vector<Vec3d> near_points(const Mesh& mesh, std::size_t n, std::uint64_t seed,
                               const Params& params) {
  const double sigma = params.get_real("sigma") * mesh.bounds().diagonal();
  if (!(sigma >= 0)) throw InputError("query kind 'near': sigma must be >= 0");
  AreaSampler sampler(mesh);
  Rng rng(seed);
  std::vector<Vec3d> pts(n);
  for (auto& p : pts) {
    const std::uint32_t t = sampler.pick(rng.uniform());
    const Vec3d a = mesh.vertex(t, 0), b = mesh.vertex(t, 1), c = mesh.vertex(t, 2);
    const double r1 = rng.uniform(), r2 = rng.uniform();
    p = uniform_in_triangle(a, b, c, r1, r2) + triangle_normal(a, b, c) * (sigma * rng.normal());
  }
  return pts;
}

std::vector<Vec3d> surface_points(const Mesh& mesh, std::size_t n, std::uint64_t seed,
                                  const Params& params) {
  const double pv = params.get_real("vertex_share"), pe = params.get_real("edge_share");
  if (!(pv >= 0 && pe >= 0 && pv + pe <= 1 + 1e-12))
    throw InputError("query kind 'surface': vertex_share and edge_share must be >= 0 with a sum <= 1");
  if (mesh.num_triangles() == 0) throw InputError(mesh.path + ": the mesh has no triangle");
  // Vertices and edges are taken from uniformly chosen triangles, so degenerate triangles get
  // their share; faces are area-weighted (and need some area only if any face point is asked).
  std::unique_ptr<AreaSampler> sampler;
  if (pv + pe < 1) sampler = std::make_unique<AreaSampler>(mesh);
  Rng rng(seed);
  std::vector<Vec3d> pts(n);
  for (auto& p : pts) {
    const double u = rng.uniform();
    if (u < pv) {
      const auto t = std::uint32_t(rng.below(mesh.num_triangles()));
      p = mesh.vertex(t, int(rng.below(3)));
    } else if (u < pv + pe) {
      const auto t = std::uint32_t(rng.below(mesh.num_triangles()));
      const int e = int(rng.below(3));
      const Vec3d a = mesh.vertex(t, e), b = mesh.vertex(t, (e + 1) % 3);
      const double s = rng.uniform();
      p = a + (b - a) * s;
    } else {
      const std::uint32_t t = sampler->pick(rng.uniform());
      const double r1 = rng.uniform(), r2 = rng.uniform();
      p = uniform_in_triangle(mesh.vertex(t, 0), mesh.vertex(t, 1), mesh.vertex(t, 2), r1, r2);
    }
  }
  return pts;
}

}  // namespace bvhbench::query_kinds_detail
