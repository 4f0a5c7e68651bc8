#pragma once
/// The triangles a query generator reads (query_kinds_detail.hpp): by index, in the mesh's order,
/// with the mesh's summary and mean edge length. A loaded Mesh is one (MeshTriangles); a mesh too
/// large for the memory `bvhbench queries` may use is another, paged from a scratch copy
/// (io/paged_triangles.hpp). The generators compute the same doubles from either, so a query set
/// is the same bytes however its mesh was held.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "harness/core/geometry.hpp"
#include "harness/core/mesh.hpp"

namespace bvhbench {

/// Where a structure built over a paged source (the haptic kinds' triangle grid) keeps what does
/// not fit in memory, and how much memory it may hold.
struct ScratchSpace {
  std::string dir;               ///< folder for temporary files (unlinked as soon as made)
  std::size_t budget_bytes = 0;  ///< the whole command's budget; each user takes its share
};

class TriangleSource {
 public:
  virtual ~TriangleSource() = default;
  /// Path, sha256, counts and box (the box of every vertex, referenced or not: Mesh::bounds).
  virtual const MeshSummary& summary() const = 0;
  /// The corners of triangle t (< num_triangles()), in the mesh's order.
  virtual std::array<Vec3d, 3> corners(std::uint32_t t) const = 0;
  /// The mean over the 3 edges of every triangle (Mesh::average_edge_length, the same sum).
  virtual double average_edge_length() const = 0;
  /// Null for a source in memory; for a paged one, where structures over it page too.
  virtual const ScratchSpace* scratch() const { return nullptr; }

  std::size_t num_triangles() const { return std::size_t(summary().triangles); }
  const std::string& path() const { return summary().path; }
};

/// A loaded mesh as a TriangleSource (it must outlive this).
class MeshTriangles final : public TriangleSource {
 public:
  explicit MeshTriangles(const Mesh& mesh) : mesh_(mesh), summary_(mesh.summary()) {}
  const MeshSummary& summary() const override { return summary_; }
  std::array<Vec3d, 3> corners(std::uint32_t t) const override {
    const auto& tri = mesh_.triangles[t];
    return {mesh_.vertices[tri[0]], mesh_.vertices[tri[1]], mesh_.vertices[tri[2]]};
  }
  double average_edge_length() const override { return mesh_.average_edge_length(); }

 private:
  const Mesh& mesh_;
  MeshSummary summary_;
};

}  // namespace bvhbench
