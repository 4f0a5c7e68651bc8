#pragma once
/// The mesh as the external build reads it: streamed in chunks of triangles (vertex indices and
/// float vertices), from a mesh file through the harness's reader or from arrays in memory, and
/// the scan in a producer thread that overlaps parsing with the work on each chunk.
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "harness/core/geometry.hpp"

namespace ebp {

using bvhbench::Vec3d;

/// Triangles per chunk of a scan (at most).
inline constexpr std::size_t kScanChunk = 1 << 16;

/// The mesh, streamed: triangles in input order with their vertex indices and float vertices.
class TriangleSource {
 public:
  virtual ~TriangleSource() = default;
  virtual std::uint64_t num_triangles() const = 0;
  virtual std::uint64_t num_vertices() const = 0;
  /// f(first triangle, n, idx[3n], xyz[9n]) over all triangles in order, in chunks. Throws
  /// std::invalid_argument / bvhbench::InputError on bad data (index out of range, non-finite).
  using Chunk = std::function<void(std::uint64_t first, std::size_t n, const std::uint32_t* idx, const float* xyz)>;
  virtual void scan(const Chunk& f) = 0;
  /// sha256 of the file's bytes (after one complete scan); "" for meshes made in code.
  virtual std::string sha256() const { return ""; }
  /// xyz[3k..3k+2] = vertex idx[k] as float in the build's frame (v - origin()), k < n: the
  /// sorted records carry vertex indices and the leaves read their coordinates here; scan() hands
  /// out the same floats. Indices come from scan() (checked there). One caller at a time.
  virtual void gather_vertices(const std::uint32_t* idx, std::size_t n, float* xyz) = 0;
  /// Vertex reads and those that missed the page cache, for a source whose vertices are paged
  /// (vertex_pages.hpp); {0, 0} when they are held.
  virtual std::pair<std::uint64_t, std::uint64_t> vertex_page_reads() const { return {0, 0}; }
  /// The frame origin, choose_origin() of all the vertices' bounds (build_parts.hpp).
  virtual Vec3d origin() const = 0;
  /// Memory the source holds (its float vertices or their page cache, buffers, an STL's weld table).
  virtual std::size_t resident_bytes() const = 0;
  /// Whether the source streams a file (false: a mesh held in memory).
  virtual bool streaming() const { return false; }
};

/// Over vertices/triangles in memory (no copy: coordinates rounded to float on the fly).
std::unique_ptr<TriangleSource> make_memory_source(const std::vector<Vec3d>& vertices,
                                                   const std::vector<std::array<std::uint32_t, 3>>& triangles);
/// Where a file source keeps its float vertices: held in memory up to `held_limit` bytes (12 B a
/// vertex), beyond that in a temporary file under `tmp_dir` behind a page cache of `cache_bytes`
/// (vertex_pages.hpp). The default holds them whatever their size.
struct VertexPaging {
  std::size_t held_limit = SIZE_MAX;
  std::string tmp_dir;
  std::size_t cache_bytes = 0;
};

/// A mesh file in any format bvhbench reads (PLY with faces or strips, OBJ, STL, OFF), streamed
/// through the harness's mesh reader (mesh_reader.hpp): the vertices read once as float (12 B
/// each; read a second time, by a second reader, when the frame origin is not 0: the float
/// coordinates are those of v - origin, which the first reading cannot know), held or paged as
/// `paging` says; the triangles re-read from the file at every scan. What the source holds besides
/// (the reader's buffers; an STL's weld table, ≈ 20–28 B per vertex) is in resident_bytes().
/// Throws InputError for a file the reader refuses (its vertices are read here; the faces'
/// problems are found at the first scan), std::runtime_error when the vertex file cannot be written.
std::unique_ptr<TriangleSource> open_mesh_source(const std::string& path, const VertexPaging& paging = {});

/// src.scan() in a producer thread (parsing the file), the chunks handed to `fn` in the calling
/// thread through a queue of at most 3 chunks. An exception on either side stops both and is
/// rethrown here.
void prefetch_scan(TriangleSource& src, const TriangleSource::Chunk& fn);

}  // namespace ebp
