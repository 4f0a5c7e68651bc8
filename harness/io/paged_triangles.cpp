// A mesh's triangles paged from a scratch copy (paged_triangles.hpp).
#include "harness/io/paged_triangles.hpp"

#include <utility>

namespace bvhbench {

PagedTriangles::PagedTriangles(MeshReader& reader, ScratchSpace scratch)
    : scratch_(std::move(scratch)),
      vertices_(scratch_.dir, "vertices", scratch_.budget_bytes / 4),
      triangles_(scratch_.dir, "triangles", scratch_.budget_bytes / 8) {
  summary_.path = reader.name();
  reader.read_vertices([&](std::uint64_t, const Vec3d* v, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i) summary_.bounds.add(v[i]);
    vertices_.append(v, n);
  });
  vertices_.finish();
  // The mean edge length in the same order as Mesh::average_edge_length: the same double.
  double edges = 0;
  reader.read_triangles([&](std::uint64_t, const Triangle* t, std::size_t n) {
    triangles_.append(t, n);
    for (std::size_t i = 0; i < n; ++i) {
      edges += perimeter(vertices_[t[i][0]], vertices_[t[i][1]], vertices_[t[i][2]]);
    }
  });
  triangles_.finish();
  summary_.vertices = reader.num_vertices();
  summary_.triangles = reader.num_triangles();
  summary_.sha256 = reader.sha256();
  if (summary_.triangles > 0) average_edge_length_ = edges / (3.0 * double(summary_.triangles));
}

PagedTriangles::PagedTriangles(const std::string& path, ScratchSpace scratch, Progress* progress)
    : PagedTriangles(*MeshReader::open(path, progress), std::move(scratch)) {}

std::uint64_t in_memory_generation_bytes(std::uint64_t vertices, std::uint64_t triangles) {
  return vertices * sizeof(Vec3d) + triangles * (sizeof(Triangle) + 8);
}

}  // namespace bvhbench
