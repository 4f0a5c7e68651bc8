#pragma once
/// External-memory build of the `.ebp` store (OUT_OF_CORE.md, "`bvhbench ebp build`"):
/// the mesh is streamed (never held in double precision), the (leaf cell, triangle) records are
/// sorted in runs that fit the memory budget, spilled to a temporary directory and merged; leaves
/// and inner nodes are built in octcode order from the merged stream with the in-memory builder's
/// own code (ebp_build_parts.hpp) and written page by page as subtrees complete; the colouring runs
/// over the node skeleton at the end and is patched into the pages (checksums updated). The
/// store is the one `write_store(build_octree(...))` writes: same pages, byte for byte.
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "methods/ebp_octree/build/mesh_source.hpp"
#include "methods/ebp_octree/core/octree.hpp"

namespace ebp {

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

/// Builds the store at `path` (written to a temporary beside it, fsync'ed, renamed; on any failure the
/// temporary and the run files are removed and the exception propagates).
ExtBuildReport build_store_external(TriangleSource& src, const std::string& path, const ExtBuildOptions& opt);

}  // namespace ebp
