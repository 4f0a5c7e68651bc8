#pragma once
/// A mesh's triangles paged from a scratch copy, for query generation within a memory budget
/// (`bvhbench queries --memory-budget`): one streamed pass over the mesh file writes its vertices
/// (double, as read) and triangles (vertex indices) in the file's order to temporary files in the
/// scratch folder, read back by index through fixed page caches (util/scratch_array.hpp). The
/// generators read the same doubles as from the loaded mesh, so a query set is the same bytes.
///
/// Memory: a quarter of the budget caches vertices, an eighth triangles; the haptic kinds' grid
/// takes three eighths more (triangle_source.hpp: ScratchSpace). Disk: 24 bytes a vertex and
/// 12 a triangle, plus the grid's ids (about 8 bytes a triangle), all unlinked as soon as made.
/// Reads are fast where the faces of one region of the surface reference vertices stored near
/// each other, as a scanner's or a generator's meshes do; other meshes are still read, a page
/// read per miss.
#include <cstdint>
#include <memory>
#include <string>

#include "harness/core/triangle_source.hpp"
#include "harness/io/mesh_reader.hpp"
#include "harness/util/scratch_array.hpp"

namespace bvhbench {

class Progress;

class PagedTriangles final : public TriangleSource {
 public:
  /// Reads every vertex and triangle of `reader` (the same checks and messages as load_mesh) into
  /// scratch files in `scratch.dir`. Throws InputError for a bad mesh or a folder it cannot write.
  PagedTriangles(MeshReader& reader, ScratchSpace scratch);
  /// The same from the mesh file at `path`; `progress` (optional) is advanced over its bytes.
  PagedTriangles(const std::string& path, ScratchSpace scratch, Progress* progress = nullptr);

  const MeshSummary& summary() const override { return summary_; }
  std::array<Vec3d, 3> corners(std::uint32_t t) const override {
    const Triangle tri = triangles_[t];
    return {vertices_[tri[0]], vertices_[tri[1]], vertices_[tri[2]]};
  }
  double average_edge_length() const override { return average_edge_length_; }
  const ScratchSpace* scratch() const override { return &scratch_; }

 private:
  ScratchSpace scratch_;
  MeshSummary summary_;
  ScratchArray<Vec3d> vertices_;
  ScratchArray<Triangle> triangles_;
  double average_edge_length_ = 0;
};

/// What generating a query set on a loaded mesh of these counts holds at its peak, in bytes: the
/// mesh (24 bytes a vertex, 12 a triangle) and the haptic kinds' grid (about 8 a triangle).
std::uint64_t in_memory_generation_bytes(std::uint64_t vertices, std::uint64_t triangles);

}  // namespace bvhbench
