#pragma once
/// External-memory build of the `.ebp` store (OUT_OF_CORE.md, "`bvhbench ebp build`"):
/// the mesh is streamed (never held in double precision), the (leaf cell, triangle) records are
/// sorted in runs that fit the memory budget, spilled to a temporary directory and merged; leaves
/// and inner nodes are built in octcode order from the merged stream with the in-memory builder's
/// own code (ebp_build_parts.hpp) and written page by page as subtrees complete; the colouring runs
/// over the node skeleton at the end and is patched into the pages (checksums updated). The
/// store is the one `write_store(Octree::build(...))` writes: same pages, byte for byte.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "methods/ebp_octree/core/octree.hpp"

namespace ebp {

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
  /// The vertices as float (x, y, z per vertex, 3 × num_vertices()), held by the source: the
  /// sorted records carry vertex indices and the leaves read their coordinates here.
  virtual const float* float_vertices() const = 0;
  /// Memory the source holds (its float vertices, buffers, an STL's weld table).
  virtual std::size_t resident_bytes() const = 0;
  /// Whether the source streams a file (false: a mesh held in memory).
  virtual bool streaming() const { return false; }
};

/// Over vertices/triangles in memory (no copy: coordinates rounded to float on the fly).
std::unique_ptr<TriangleSource> make_memory_source(const std::vector<Vec3d>& vertices,
                                                   const std::vector<std::array<std::uint32_t, 3>>& triangles);
/// A mesh file in any format bvhbench reads (PLY with faces or strips, OBJ, STL, OFF), streamed
/// through the harness's mesh reader (mesh_reader.hpp): the vertices read once and held as float
/// (12 B each), the triangles re-read from the file at every scan. What the source holds besides
/// (the reader's buffers; an STL's weld table, ≈ 20–28 B per vertex) is in resident_bytes().
/// Throws InputError for a file the reader refuses (its vertices are read here; the faces'
/// problems are found at the first scan).
std::unique_ptr<TriangleSource> open_mesh_source(const std::string& path);

struct ExtBuildOptions {
  BuildParams params;
  std::size_t memory_budget = std::size_t(1) << 30;  ///< bytes
  std::string tmp_dir;                                ///< existing directory for the sorted runs
  std::size_t page_target = 16 * 1024;
  /// The info section (JSON) from the finished build's report.
  std::function<std::string(const struct ExtBuildReport&)> info_json;
  /// Progress: phase name and fraction of the whole build in [0, 1].
  std::function<void(const char* phase, double fraction)> progress;
  /// Called often (between chunks, batches, pages): throw to abort (interrupts).
  std::function<void()> check;
  /// Test hook: called before each page is written.
  std::function<void(std::uint32_t page)> before_page;
  /// Testing: run buffer size in bytes (0: from the budget).
  std::size_t run_bytes = 0;
};

struct ExtBuildReport {
  Stats stats;
  bool closed = false;
  std::uint64_t pages = 0, file_bytes = 0;
  std::uint64_t runs = 0, run_capacity_records = 0, spill_bytes = 0, records = 0;
  std::uint64_t skeleton_bytes = 0, top_nodes = 0;
  /// What the build sets aside before its working memory (float vertices, skeleton and top tree
  /// estimate, a fixed reserve) + 8 MiB: a smaller budget is exceeded.
  std::uint64_t min_budget_bytes = 0;
  double seconds_frame = 0, seconds_distribute = 0, seconds_merge_build = 0, seconds_colour = 0, seconds_total = 0;
};

/// Builds the store at `path` (written as `path + ".tmp"`, fsync'ed, renamed; on any failure the
/// temporary and the run files are removed and the exception propagates).
ExtBuildReport build_store_external(TriangleSource& src, const std::string& path, const ExtBuildOptions& opt);

}  // namespace ebp
