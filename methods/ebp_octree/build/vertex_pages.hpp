#pragma once
/// The float vertices of a mesh too large to hold them within the build's memory budget: kept in
/// a temporary file and read back through a fixed page cache (OUT_OF_CORE.md, "Vertices out of
/// core"; the file and its cache are the harness's ScratchFile, util/scratch_array.hpp). The
/// build reads vertices by index where triangles need them: the scans in the file's face order
/// and the leaf batches in octcode order. Both touch the vertices of one region of the surface at
/// a time in the meshes a scanner or a generator writes, so a cache of a fraction of the vertices
/// serves almost every read; a mesh whose faces reference vertices at random is still built, with
/// one page read per miss (the build prints the hit rate).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "harness/util/scratch_array.hpp"

namespace ebp {

class VertexPages {
 public:
  /// Vertices per page (12 B each).
  static constexpr std::size_t kPageVertices = bvhbench::ScratchFile::kPageRecords;

  /// A temporary file for `vertices` vertices in `dir` (unlinked at once, so that nothing is left
  /// behind whatever happens) and a cache of `cache_bytes` (at least two pages). Throws
  /// bvhbench::InputError naming the directory when the file cannot be created.
  VertexPages(const std::string& dir, std::uint64_t vertices, std::size_t cache_bytes);

  /// Writing, in order from vertex 0: the next n vertices (x, y, z each). rewind() starts again
  /// from vertex 0 (the coordinates written a second time, in the build's frame); finish() flushes
  /// and must come before the first gather (std::logic_error if other than vertices() were written).
  void append(const float* xyz, std::size_t n);
  void rewind();
  void finish();

  /// xyz[3k..3k+2] = vertex idx[k], k < n. Indices are checked by the caller (< vertices()).
  void gather(const std::uint32_t* idx, std::size_t n, float* xyz);

  std::uint64_t vertices() const { return vertices_; }
  /// The cache and the write buffer.
  std::size_t resident_bytes() const { return file_->resident_bytes(); }
  std::uint64_t reads() const { return file_->reads(); }
  std::uint64_t misses() const { return file_->misses(); }

 private:
  std::string dir_;
  std::uint64_t vertices_ = 0;
  std::size_t cache_bytes_ = 0;
  std::unique_ptr<bvhbench::ScratchFile> file_;
};

}  // namespace ebp
