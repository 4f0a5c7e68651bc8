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

namespace {

/// The running sum of triangle areas over triangles [t0, t1) from `sum`, calling
/// at(t, sum) after each triangle until it returns true; returns the sum. The sampler's pass over
/// the whole mesh and a pick's pass over one chunk both add through here, one triangle at a time
/// in triangle order, so a chunk's running sums are the same doubles both times.
template <class At>
double add_areas(const TriangleSource& mesh, std::size_t t0, std::size_t t1, double sum, At&& at) {
  for (std::size_t t = t0; t < t1; ++t) {
    const auto [a, b, c] = mesh.corners(std::uint32_t(t));
    sum += 0.5 * norm(cross(b - a, c - a));
    if (at(t, sum)) break;
  }
  return sum;
}

}  // namespace

AreaSampler::AreaSampler(const TriangleSource& mesh) : mesh_(mesh) {
  const std::size_t nt = mesh.num_triangles();
  chunk_end_.reserve((nt + kChunk - 1) / kChunk);
  double sum = 0;
  for (std::size_t t0 = 0; t0 < nt; t0 += kChunk)
    chunk_end_.push_back(sum = add_areas(mesh, t0, std::min(nt, t0 + kChunk), sum, [](std::size_t, double) { return false; }));
  if (!(sum > 0) || !std::isfinite(sum))
    throw InputError(mesh.path() + ": the mesh has no surface area to sample");
}

std::uint32_t AreaSampler::pick(double u) const {
  const double x = u * chunk_end_.back();
  // The first chunk whose running sum exceeds x holds the first triangle whose running sum
  // does (the sums never decrease); none: the last triangle. Zero-area triangles (the same sum
  // as their predecessor) can never be the first to exceed it.
  const auto it = std::upper_bound(chunk_end_.begin(), chunk_end_.end(), x);
  if (it == chunk_end_.end()) return std::uint32_t(mesh_.num_triangles() - 1);
  const std::size_t c = std::size_t(it - chunk_end_.begin());
  const std::size_t t0 = c * kChunk, t1 = std::min(mesh_.num_triangles(), t0 + kChunk);
  std::size_t found = t1 - 1;
  add_areas(mesh_, t0, t1, c > 0 ? chunk_end_[c - 1] : 0.0, [&](std::size_t t, double sum) {
    if (!(sum > x)) return false;
    found = t;
    return true;
  });
  return std::uint32_t(found);
}

Vec3d uniform_in_triangle(const Vec3d& a, const Vec3d& b, const Vec3d& c, double r1, double r2) {
  const double s = std::sqrt(r1);
  return a * (1 - s) + b * (s * (1 - r2)) + c * (s * r2);
}

std::vector<Vec3d> near_points(const TriangleSource& mesh, std::size_t n, std::uint64_t seed,
                               const Params& params) {
  const double sigma = params.get_real("sigma") * mesh.summary().bounds.diagonal();
  if (!(sigma >= 0)) throw InputError("query kind 'near': sigma must be >= 0");
  AreaSampler sampler(mesh);
  Rng rng(seed);
  std::vector<Vec3d> pts(n);
  for (auto& p : pts) {
    const std::uint32_t t = sampler.pick(rng.uniform());
    const auto [a, b, c] = mesh.corners(t);
    const double r1 = rng.uniform(), r2 = rng.uniform();
    p = uniform_in_triangle(a, b, c, r1, r2) + triangle_normal(a, b, c) * (sigma * rng.normal());
  }
  return pts;
}

std::vector<Vec3d> surface_points(const TriangleSource& mesh, std::size_t n, std::uint64_t seed,
                                  const Params& params) {
  const double pv = params.get_real("vertex_share"), pe = params.get_real("edge_share");
  if (!(pv >= 0 && pe >= 0 && pv + pe <= 1 + 1e-12))
    throw InputError("query kind 'surface': vertex_share and edge_share must be >= 0 with a sum <= 1");
  if (mesh.num_triangles() == 0) throw InputError(mesh.path() + ": the mesh has no triangle");
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
      p = mesh.corners(t)[rng.below(3)];
    } else if (u < pv + pe) {
      const auto t = std::uint32_t(rng.below(mesh.num_triangles()));
      const int e = int(rng.below(3));
      const std::array<Vec3d, 3> v = mesh.corners(t);
      const Vec3d a = v[std::size_t(e)], b = v[std::size_t((e + 1) % 3)];
      const double s = rng.uniform();
      p = a + (b - a) * s;
    } else {
      const std::uint32_t t = sampler->pick(rng.uniform());
      const double r1 = rng.uniform(), r2 = rng.uniform();
      const auto [a, b, c] = mesh.corners(t);
      p = uniform_in_triangle(a, b, c, r1, r2);
    }
  }
  return pts;
}

}  // namespace bvhbench::query_kinds_detail
