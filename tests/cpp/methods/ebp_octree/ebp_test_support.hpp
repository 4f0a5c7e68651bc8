#pragma once
// What the EBP-Octree's tests share: a brute-force reference on the float-rounded geometry,
// generated meshes (icosphere, torus), query points, an exact triangle/box clipper, and a build
// with default parameters.
#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "harness/core/mesh.hpp"
#include "methods/ebp_octree/build/octree_build.hpp"
#include "methods/ebp_octree/core/octree.hpp"
#include "methods/ebp_octree/core/predicates.hpp"
#include "methods/ebp_octree/store/reader.hpp"
#include "methods/ebp_octree/store/writer.hpp"
#include "support/test_support.hpp"

namespace ebp_test {

using namespace ebp;
using bvhbench::Mesh;
using Tris = std::vector<std::array<std::uint32_t, 3>>;

inline std::string shared_mesh(const std::string& name) { return std::string(BVHBENCH_SHARED_DIR) + "/meshes/" + name; }

/// The brute-force reference, the same formulas as methods/brute_force (on the float-rounded
/// geometry the octree uses, so that answers are comparable to the last bit of the predicates).
struct Reference {
  std::vector<Vec3d> v;
  Tris f;
  Reference(const std::vector<Vec3d>& vin, const Tris& fin) : f(fin) {
    for (auto& p : vin) v.push_back(round_to_float(p));
  }
  double winding(const Vec3d& p) const {
    double w = 0;
    for (auto& t : f) w += bvhbench::triangle_winding(p, v[t[0]], v[t[1]], v[t[2]]);
    return w;
  }
  double dist(const Vec3d& p, std::int64_t* tri = nullptr) const {
    double best = 1e300;
    std::int64_t bi = -1;
    for (std::size_t i = 0; i < f.size(); ++i) {
      const Vec3d q = bvhbench::closest_point_on_triangle(p, v[f[i][0]], v[f[i][1]], v[f[i][2]]);
      const double d2 = squared_norm(q - p);
      if (d2 < best) { best = d2; bi = std::int64_t(i); }
    }
    if (tri) *tri = bi;
    return std::sqrt(best);
  }
  double tri_dist(const Vec3d& p, std::int64_t i) const {
    return norm(bvhbench::closest_point_on_triangle(p, v[f[i][0]], v[f[i][1]], v[f[i][2]]) - p);
  }
  Box3d bounds() const {
    Box3d b;
    for (auto& p : v) b.add(p);
    return b;
  }
};

inline Mesh icosphere(int subdiv, double r = 1.0, Vec3d c = {0.1, -0.2, 0.3}) {
  Mesh m;
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vec3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                          {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  Tris f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
            {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
            {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (auto& p : v) p = bvhbench::normalized(p);
  for (int s = 0; s < subdiv; ++s) {
    std::map<std::pair<std::uint32_t, std::uint32_t>, std::uint32_t> mid;
    auto midpoint = [&](std::uint32_t a, std::uint32_t b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back(bvhbench::normalized((v[a] + v[b]) * 0.5));
      return mid[key] = std::uint32_t(v.size() - 1);
    };
    Tris g;
    for (auto& tr : f) {
      const std::uint32_t a = midpoint(tr[0], tr[1]), b = midpoint(tr[1], tr[2]), c = midpoint(tr[2], tr[0]);
      g.push_back({tr[0], a, c});
      g.push_back({tr[1], b, a});
      g.push_back({tr[2], c, b});
      g.push_back({a, b, c});
    }
    f = g;
  }
  for (auto& p : v) m.vertices.push_back(p * r + c);
  m.triangles = f;
  return m;
}

inline Mesh torus(int nu, int nv, double R = 1.0, double r = 0.35) {
  Mesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2 * M_PI * i / nu, w = 2 * M_PI * j / nv;
      m.vertices.push_back({(R + r * std::cos(w)) * std::cos(u), (R + r * std::cos(w)) * std::sin(u), r * std::sin(w)});
    }
  auto id = [&](int i, int j) { return std::uint32_t(((i + nu) % nu) * nv + ((j + nv) % nv)); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      m.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      m.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  return m;
}

/// Query points: uniform in the box grown by 10 %, and near the surface (on random triangles,
/// pushed along the normal by up to 2 % of the diagonal either way).
inline std::vector<Vec3d> sample_points(const Reference& ref, int n_uniform, int n_near, std::uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  const Box3d b = ref.bounds();
  const Vec3d e = b.extent();
  const double diag = b.diagonal();
  std::vector<Vec3d> pts;
  for (int i = 0; i < n_uniform; ++i)
    pts.push_back({b.lo.x - 0.1 * e.x + 1.2 * e.x * U(rng), b.lo.y - 0.1 * e.y + 1.2 * e.y * U(rng),
                   b.lo.z - 0.1 * e.z + 1.2 * e.z * U(rng)});
  std::uniform_int_distribution<std::size_t> T(0, ref.f.size() - 1);
  for (int i = 0; i < n_near; ++i) {
    const auto& t = ref.f[T(rng)];
    double u = U(rng), v = U(rng);
    if (u + v > 1) { u = 1 - u; v = 1 - v; }
    const Vec3d a = ref.v[t[0]], bb = ref.v[t[1]], c = ref.v[t[2]];
    const Vec3d p = a + (bb - a) * u + (c - a) * v;
    const Vec3d n = bvhbench::triangle_normal(a, bb, c);
    pts.push_back(p + n * ((U(rng) * 2 - 1) * 0.02 * diag));
  }
  return pts;
}

/// Exact-box clipping (no growth): the polygon triangle ∩ [lo - grow, hi + grow].
inline std::vector<Vec3d> clip_exact(const Vec3d& lo, const Vec3d& hi, const Vec3d& a, const Vec3d& b, const Vec3d& c,
                              double grow = 0.0) {
  std::vector<Vec3d> poly = {a, b, c};
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const double bound = side == 0 ? lo[axis] - grow : hi[axis] + grow;
      std::vector<Vec3d> out;
      for (std::size_t i = 0; i < poly.size(); ++i) {
        const Vec3d P = poly[i], Q = poly[(i + 1) % poly.size()];
        auto in = [&](const Vec3d& X) { return side == 0 ? X[axis] >= bound : X[axis] <= bound; };
        if (in(P)) out.push_back(P);
        if (in(P) != in(Q)) {
          Vec3d X = P + (Q - P) * ((bound - P[axis]) / (Q[axis] - P[axis]));
          X[axis] = bound;
          out.push_back(X);
        }
      }
      poly = out;
      if (poly.empty()) return poly;
    }
  return poly;
}

inline Octree build(const Mesh& m, BuildParams bp = {}) { return build_octree(m.vertices, m.triangles, bp); }

/// The tree written to a store of 4 KiB pages and read back whole (StoreReader::load_all, which
/// computes the derived data again).
inline Octree through_store(const Octree& t, const std::string& name) {
  bvhbench::test::TmpDir d("ebp_" + name);
  StoreWriteOptions wo;
  wo.page_target = 4096;
  wo.info_json = "{}";
  const std::string path = (d.p / (name + ".ebp")).string();
  write_store_atomic(t, path, wo);
  return StoreReader(path).load_all();
}

}  // namespace ebp_test
