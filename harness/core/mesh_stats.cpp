#include "harness/core/mesh_stats.hpp"

#include <algorithm>
#include <vector>

#include "harness/core/mesh.hpp"
#include "harness/core/oracle.hpp"

namespace bvhbench {

MeshStats mesh_stats(const Mesh& mesh) {
  MeshStats s;
  s.bounds = mesh.bounds();
  std::vector<bool> used(mesh.vertices.size(), false);
  // Each side u->v of a triangle, as the key min << 32 | max, in `fwd` if u < v, else in `bwd`:
  // after sorting, an edge's two counts are the lengths of its runs in both.
  std::vector<std::uint64_t> fwd, bwd;
  fwd.reserve(3 * mesh.triangles.size() / 2 + 1);
  bwd.reserve(3 * mesh.triangles.size() / 2 + 1);
  for (const auto& t : mesh.triangles) {
    for (int k = 0; k < 3; ++k) {
      used[t[k]] = true;
      const std::uint64_t u = t[k], v = t[(k + 1) % 3];
      if (u < v) fwd.push_back(u << 32 | v);
      if (u > v) bwd.push_back(v << 32 | u);
    }
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2] ||
        collinear_exact(mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]]))
      ++s.degenerate_triangles;
  }
  s.unreferenced_vertices = std::uint64_t(std::count(used.begin(), used.end(), false));
  std::sort(fwd.begin(), fwd.end());
  std::sort(bwd.begin(), bwd.end());
  std::size_t i = 0, j = 0;
  while (i < fwd.size() || j < bwd.size()) {
    const std::uint64_t key = j == bwd.size() || (i < fwd.size() && fwd[i] < bwd[j]) ? fwd[i] : bwd[j];
    std::uint64_t f = 0, b = 0;
    for (; i < fwd.size() && fwd[i] == key; ++i) ++f;
    for (; j < bwd.size() && bwd[j] == key; ++j) ++b;
    ++s.edges;
    if (f + b == 1) ++s.boundary_edges;
    else if (f + b > 2) ++s.nonmanifold_edges;
    else if (f != b) ++s.misoriented_edges;
    if (f != b) ++s.unbalanced_edges;
  }
  return s;
}

}  // namespace bvhbench
