#pragma once
/// The float vertices of a mesh too large to hold them within the build's memory budget: kept in
/// a temporary file and read back through a fixed page cache (OUT_OF_CORE.md, "Vertices out of
/// core"). The build reads vertices by index where triangles need them: the scans in the file's
/// face order and the leaf batches in octcode order. Both touch the vertices of one region of the
/// surface at a time in the meshes a scanner or a generator writes, so a cache of a fraction of
/// the vertices serves almost every read; a mesh whose faces reference vertices at random is
/// still built, with one page read per miss (the build prints the hit rate).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace ebp {

class VertexPages {
 public:
  /// Vertices per page (12 B each: 12 KiB pages).
  static constexpr std::size_t kPageVertices = 1024;

  /// A temporary file for `vertices` vertices in `dir` (unlinked at once, so that nothing is left
  /// behind whatever happens) and a cache of `cache_bytes` (at least two pages). Throws
  /// std::runtime_error naming the directory when the file cannot be created.
  VertexPages(const std::string& dir, std::uint64_t vertices, std::size_t cache_bytes);
  ~VertexPages();
  VertexPages(const VertexPages&) = delete;
  VertexPages& operator=(const VertexPages&) = delete;

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
  std::size_t resident_bytes() const;
  std::uint64_t reads() const { return reads_; }
  std::uint64_t misses() const { return misses_; }

 private:
  const float* page(std::uint64_t p);
  void flush();

  std::string dir_;
  int fd_ = -1;
  std::uint64_t vertices_ = 0, num_pages_ = 0;
  std::uint64_t written_ = 0;    ///< vertices appended since the last rewind
  std::uint64_t flushed_ = 0;    ///< floats in the file since the last rewind
  std::vector<float> wbuf_;      ///< one page being written
  std::vector<float> slots_;     ///< the cache: kPageVertices * 3 floats per slot
  std::vector<std::int32_t> slot_of_;      ///< page -> slot, -1 when not cached
  std::vector<std::uint64_t> page_in_;     ///< slot -> page (UINT64_MAX when free)
  std::vector<std::uint8_t> referenced_;   ///< slot -> the clock's second chance
  std::size_t hand_ = 0;
  std::uint64_t last_page_ = UINT64_MAX;
  const float* last_ = nullptr;
  std::uint64_t reads_ = 0, misses_ = 0;
};

}  // namespace ebp
