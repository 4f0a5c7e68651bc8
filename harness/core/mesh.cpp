// The Mesh's own figures (bounds, average edge length).
#include "harness/core/mesh.hpp"

namespace bvhbench {

Box3d Mesh::bounds() const {
  Box3d b;
  for (const Vec3d& v : vertices) b.add(v);
  return b;
}

MeshSummary Mesh::summary() const { return {path, sha256, triangles.size(), vertices.size(), bounds()}; }

double Mesh::average_edge_length() const {
  if (triangles.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& t : triangles) {
    const Vec3d& a = vertices[t[0]];
    const Vec3d& b = vertices[t[1]];
    const Vec3d& c = vertices[t[2]];
    sum += perimeter(a, b, c);
  }
  return sum / (3.0 * double(triangles.size()));
}

}  // namespace bvhbench
